// Interop test: a .tlog written by uavsim-server --log-dir is read back record by record by node-mavlink (an
// independent MAVLink implementation): every record is an 8-byte big-endian microsecond stamp and one whole
// frame with a valid checksum, stamps never go backwards, and the log spans the run's sim time.
//
// usage: node tlog_parse.mjs --server PATH/uavsim-server --world models/worlds/empty.xml --dir TMPDIR
import { spawnSync } from 'child_process'
import { readFileSync, mkdirSync } from 'fs'
import { Readable } from 'stream'

let nm
try {
  nm = await import('node-mavlink')
} catch (e) {
  console.log('tlog_parse: SKIP: node-mavlink is not installed (run npm install in tests/interop)')
  process.exit(77)
}
const { MavLinkPacketSplitter, MavLinkPacketParser, minimal, common, ardupilotmega } = nm
const REGISTRY = { ...minimal.REGISTRY, ...common.REGISTRY, ...ardupilotmega.REGISTRY }
const args = Object.fromEntries(process.argv.slice(2).reduce((a, v, i, all) =>
  (v.startsWith('--') ? [...a, [v.slice(2), all[i + 1]]] : a), []))
function fail(why) {
  console.error(`tlog_parse: FAIL: ${why}`)
  process.exit(1)
}

// a 5 s run as fast as possible; vehicle 0 streams to a UDP port nobody listens on, which the log records
const dir = `${args.dir}/tlog_interop_${process.pid}`
mkdirSync(dir, { recursive: true })
const run = spawnSync(args.server, [args.world, '--rate', '0', '--duration', '5', '--mavlink-port', '0',
  '--api-port', '-1', '--no-cameras', '--quiet', '--out', 'udp:127.0.0.1:9', '--log-dir', dir], { encoding: 'utf8' })
if (run.status !== 0) fail(`server exited ${run.status}: ${run.stdout}${run.stderr}`)

// split the log into records by the frame lengths in the MAVLink headers
const bytes = readFileSync(`${dir}/uav0.tlog`)
const stamps = []
const frames = []
for (let at = 0; at + 8 < bytes.length;) {
  const stamp = bytes.readBigUInt64BE(at)
  const f = bytes.subarray(at + 8)
  const len = f[0] === 0xFE ? 8 + f[1] : f[0] === 0xFD ? 12 + f[1] + ((f[2] & 1) ? 13 : 0) : 0
  if (len === 0 || len > f.length) fail(`record at byte ${at} does not hold a frame`)
  stamps.push(stamp)
  frames.push(Buffer.from(f.subarray(0, len)))
  at += 8 + len
}
if (frames.length < 20) fail(`only ${frames.length} records`)
for (let i = 1; i < stamps.length; i++) {
  if (stamps[i] < stamps[i - 1]) fail(`stamp ${i} goes backwards: ${stamps[i - 1]} -> ${stamps[i]}`)
}
const last = Number(stamps[stamps.length - 1])
if (last > 5.0e6 || last < 4.0e6) fail(`the last stamp ${last} us is not near the run's 5 s of sim time`)

// node-mavlink parses each record on its own: one packet each, of a message it knows
let packets = 0
const names = new Set()
await new Promise((resolve, reject) => {
  const reader = Readable.from(frames).pipe(new MavLinkPacketSplitter()).pipe(new MavLinkPacketParser())
  reader.on('data', (p) => {
    packets++
    const clazz = REGISTRY[p.header.msgid]
    if (clazz) names.add(clazz.MSG_NAME)
  })
  reader.on('end', resolve)
  reader.on('error', reject)
})
if (packets !== frames.length) fail(`node-mavlink parsed ${packets} packets of ${frames.length} records`)
for (const need of ['HEARTBEAT', 'SYS_STATUS', 'GLOBAL_POSITION_INT']) {
  if (!names.has(need)) fail(`no ${need} in the log (${[...names].join(', ')})`)
}
console.log(`tlog_parse: OK: ${frames.length} records, ${names.size} message types, last stamp ${last} us`)
