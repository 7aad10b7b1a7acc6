// Interop test: node-mavlink (an independent MAVLink implementation) acts as a ground station and flies
// vehicle 0 of a uavsim server: heartbeat, GUIDED, arm, take off to 10 m, go to a local NED point, upload a
// 3-waypoint mission and fly it in AUTO, set a parameter and read it back, LAND, wait for disarm.
// Exit 0 only if every step was observed in telemetry. Progress is measured in telemetry time_boot_ms
// (simulation time). The server runs at 5x real time, not as fast as possible: this ground station is not on
// the lockstep clock, and at full speed (~70x) a node process starved of CPU for 70 ms by a parallel test
// let 5 s of sim time pass before it saw an ACK (seen once in a CI run of the whole suite).
//
// usage: node gcs_flight.mjs --server PATH/uavsim-server --world models/worlds/empty.xml
//        node gcs_flight.mjs --port 5760            (against a server that is already running)
import { spawn } from 'child_process'
import { connect } from 'net'

// node-mavlink comes from `npm install` in tests/interop (scripts/install_deps.sh does it); without it, skip
let nm
try {
  nm = await import('node-mavlink')
} catch (e) {
  console.log('gcs_flight: SKIP: node-mavlink is not installed (run npm install in tests/interop)')
  process.exit(77)
}
const { MavLinkPacketSplitter, MavLinkPacketParser, MavLinkProtocolV2, send, minimal, common, ardupilotmega } = nm

const REGISTRY = { ...minimal.REGISTRY, ...common.REGISTRY, ...ardupilotmega.REGISTRY }
const args = Object.fromEntries(process.argv.slice(2).reduce((a, v, i, all) =>
  (v.startsWith('--') ? [...a, [v.slice(2), all[i + 1]]] : a), []))
const WALL_LIMIT_MS = 100000
const R = 6378100  // seed eq. 6.1

let server = null
function fail(why) {
  console.error(`gcs_flight: FAIL: ${why}`)
  if (server) server.kill('SIGTERM')
  process.exit(1)
}
setTimeout(() => fail('wall-clock limit reached'), WALL_LIMIT_MS).unref()

// --- start the server (ephemeral MAVLink port, read from its banner) or use --port ---
async function serverPort() {
  if (args.port) return Number(args.port)
  server = spawn(args.server, [args.world, '--rate', args.rate ?? '5', '--duration', args.duration ?? '2000',
    '--mavlink-port', '0'], { stdio: ['ignore', 'pipe', 'inherit'] })
  server.on('exit', (code) => { if (!done) fail(`server exited early (code ${code})`) })
  return await new Promise((resolve) => {
    let text = ''
    server.stdout.on('data', (d) => {
      text += d.toString()
      const m = text.match(/MAVLink on tcp:[\d.]+:(\d+)/)
      if (m) resolve(Number(m[1]))
    })
  })
}

let done = false
const port = await serverPort()
const socket = connect({ host: '127.0.0.1', port })
socket.on('error', (e) => fail(`socket: ${e.message}`))
const protocol = new MavLinkProtocolV2(255, 190)
const reader = socket.pipe(new MavLinkPacketSplitter()).pipe(new MavLinkPacketParser())

// --- telemetry state ---
const state = { timeMs: 0, hb: null, sys: null, gpos: null, lpos: null, acks: [], reached: new Set(),
  params: new Map(), missionRequests: [], missionAcks: [], gotHeartbeats: 0 }
const waiters = new Set()
reader.on('data', (packet) => {
  const clazz = REGISTRY[packet.header.msgid]
  if (!clazz || packet.header.sysid !== 1) return
  const m = packet.protocol.data(packet.payload, clazz)
  if (m.timeBootMs !== undefined) state.timeMs = Math.max(state.timeMs, m.timeBootMs)
  switch (clazz) {
    case minimal.Heartbeat:
      state.hb = m
      state.gotHeartbeats++
      // a GCS heartbeat per vehicle heartbeat: 1 Hz in sim time, whatever the clock rate
      send(socket, Object.assign(new minimal.Heartbeat(), { type: 6, autopilot: 8, baseMode: 0, customMode: 0,
        systemStatus: 4, mavlinkVersion: 3 }), protocol)
      break
    case common.SysStatus: state.sys = m; break
    case common.GlobalPositionInt: state.gpos = m; break
    case common.LocalPositionNed: state.lpos = m; break
    case common.CommandAck: state.acks.push(m); break
    case common.MissionItemReached: state.reached.add(m.seq); break
    case common.ParamValue: state.params.set(m.paramId.replace(/\0.*$/, ''), m.paramValue); break
    case common.MissionRequest: case common.MissionRequestInt: state.missionRequests.push(m.seq); break
    case common.MissionAck: state.missionAcks.push(m.type); break
  }
  for (const w of [...waiters]) w()
})

// waits until pred() holds, at most simS seconds of telemetry time
function until(what, pred, simS) {
  return new Promise((resolve) => {
    const start = state.timeMs
    const check = () => {
      if (pred()) { waiters.delete(check); resolve(); return }
      if (state.timeMs - start > simS * 1000) { waiters.delete(check); fail(`${what}: not seen within ${simS} s sim`) }
    }
    waiters.add(check)
    check()
  })
}
function step(name) { console.log(`gcs_flight: t=${(state.timeMs / 1000).toFixed(1)}s ok: ${name}`) }

async function command(cmd, params, what) {
  const c = new common.CommandLong()
  c.targetSystem = 1; c.targetComponent = 1; c.command = cmd; c.confirmation = 0
  ;[c._param1, c._param2, c._param3, c._param4, c._param5, c._param6, c._param7] = [...params, 0, 0, 0, 0, 0, 0, 0]
  const before = state.acks.length
  await send(socket, c, protocol)
  await until(`${what} ack`, () => state.acks.slice(before).some((a) => a.command === cmd), 5)
  const ack = state.acks.slice(before).find((a) => a.command === cmd)
  if (ack.result !== 0) fail(`${what}: COMMAND_ACK result ${ack.result}`)
}

// 1. heartbeat from an ArduCopter quad
await until('vehicle HEARTBEAT', () => state.hb && state.hb.autopilot === 3 && state.hb.type === 2, 10)
step('heartbeat')
// ready: GPS and pre-arm healthy in SYS_STATUS
await until('pre-arm healthy', () => state.sys && (state.sys.onboardControlSensorsHealth & 0x10000020) === 0x10000020, 60)
step('pre-arm checks pass')
// 2. GUIDED
await command(176, [1, 4], 'set GUIDED')
await until('GUIDED in HEARTBEAT', () => state.hb.customMode === 4, 5)
step('mode GUIDED')
// 3. arm
await command(400, [1], 'arm')
await until('armed in HEARTBEAT', () => (state.hb.baseMode & 128) !== 0, 5)
step('armed')
// 4. take off to 10 m
await command(22, [0, 0, 0, 0, 0, 0, 10], 'takeoff')
await until('10 m relative altitude', () => state.gpos && Math.abs(state.gpos.relativeAlt / 1000 - 10) < 0.5, 40)
step('took off to 10 m')
// 5. go to local NED (20, 10, -10)
const sp = new common.SetPositionTargetLocalNed()
Object.assign(sp, { timeBootMs: 0, targetSystem: 1, targetComponent: 1, coordinateFrame: 1, typeMask: 3576,
  x: 20, y: 10, z: -10, vx: 0, vy: 0, vz: 0, afx: 0, afy: 0, afz: 0, yaw: 0, yawRate: 0 })
await send(socket, sp, protocol)
await until('local NED (20, 10, -10)', () => state.lpos && Math.hypot(state.lpos.x - 20, state.lpos.y - 10) < 1 &&
  Math.abs(state.lpos.z + 10) < 0.5, 40)
step('reached local NED (20, 10, -10)')
// 6. upload home + 3 waypoints (10 m relative), as MISSION_ITEM_INT; lat/lon from the current fix
const lat0 = state.gpos.lat / 1e7, lon0 = state.gpos.lon / 1e7
const ne = [[0, 0], [30, 0], [30, 20], [0, 20]]  // offsets from here, metres north/east
const items = ne.map(([n, e], seq) => {
  const it = new common.MissionItemInt()
  Object.assign(it, { targetSystem: 1, targetComponent: 1, seq, frame: seq === 0 ? 0 : 6, command: 16,
    current: 0, autocontinue: 1, param1: 0, param2: 0, param3: 0, param4: 0,
    x: Math.round((lat0 + (n / R) * 180 / Math.PI) * 1e7),
    y: Math.round((lon0 + (e / (R * Math.cos(lat0 * Math.PI / 180))) * 180 / Math.PI) * 1e7),
    z: seq === 0 ? 0 : 10, missionType: 0 })
  return it
})
const mc = new common.MissionCount()
Object.assign(mc, { targetSystem: 1, targetComponent: 1, count: items.length, missionType: 0, opaqueId: 0 })
let answered = 0
const answer = () => {
  while (answered < state.missionRequests.length) send(socket, items[state.missionRequests[answered++]], protocol)
}
waiters.add(answer)
await send(socket, mc, protocol)
await until('MISSION_ACK', () => state.missionAcks.length > 0, 10)
waiters.delete(answer)
if (state.missionAcks[0] !== 0) fail(`mission upload: MISSION_ACK ${state.missionAcks[0]}`)
step(`mission uploaded (${state.missionRequests.length} items requested)`)
// 7. fly it in AUTO
await command(300, [0, 0], 'MISSION_START')
await until('AUTO in HEARTBEAT', () => state.hb.customMode === 3, 5)
await until('MISSION_ITEM_REACHED 3', () => state.reached.has(3), 120)
const dn = (state.gpos.lat / 1e7 - lat0) * Math.PI / 180 * R
const de = (state.gpos.lon / 1e7 - lon0) * Math.PI / 180 * R * Math.cos(lat0 * Math.PI / 180)
if (Math.hypot(dn - 0, de - 20) > 2) fail(`after the mission the vehicle is at (${dn.toFixed(1)}, ${de.toFixed(1)})`)
step(`mission flown in AUTO (reached ${[...state.reached].join(',')})`)
// 8. set a parameter and read it back
const ps = new common.ParamSet()
Object.assign(ps, { targetSystem: 1, targetComponent: 1, paramId: 'WPNAV_SPEED', paramValue: 600, paramType: 9 })
state.params.delete('WPNAV_SPEED')
await send(socket, ps, protocol)
await until('PARAM_VALUE echo', () => state.params.get('WPNAV_SPEED') === 600, 5)
state.params.delete('WPNAV_SPEED')
const pr = new common.ParamRequestRead()
Object.assign(pr, { targetSystem: 1, targetComponent: 1, paramId: 'WPNAV_SPEED', paramIndex: -1 })
await send(socket, pr, protocol)
await until('PARAM_VALUE read back', () => state.params.get('WPNAV_SPEED') === 600, 5)
step('parameter WPNAV_SPEED set to 600 and read back')
// 9. land and wait for disarm
await command(21, [], 'LAND')
await until('disarmed after LAND', () => (state.hb.baseMode & 128) === 0 && state.hb.customMode === 9, 120)
step('landed and disarmed')

done = true
socket.end()
if (server) server.kill('SIGTERM')
console.log('gcs_flight: PASS')
process.exit(0)
