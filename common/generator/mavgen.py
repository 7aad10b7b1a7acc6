#!/usr/bin/env python3
"""Generates the uavsim MAVLink message structs, id table, enums and enum names from the dialect XML.

Usage (from the repository root):
  python3 common/generator/mavgen.py --xml <definitions>/ardupilotmega.xml \
      [--out common] [--messages common/generator/messages.txt] [--all]

Headers go to <out>/include/uavsim/common/mavlink/generated, sources to <out>/src/mavlink/generated.

Standard library only. The output is committed, so the build never needs the XML.

Protocol rules implemented here (MAVLink spec, "Serialization" and "CRC_EXTRA"):
  * wire order: base fields (before <extensions/>) stably sorted by element size, largest first;
    extension fields follow in XML order.
  * CRC_EXTRA: X.25 over "NAME " then "type name " for each sorted base field (plus one byte with the array
    length for arrays), folded to one byte as (crc & 0xFF) ^ (crc >> 8).
  * min length = base fields (v1 payload), max length = all fields (full v2 payload).
"""

import argparse
import os
import re
import sys
import xml.etree.ElementTree as ET

# element type -> (C++ type, size in bytes, wire type name used by CRC_EXTRA)
TYPES = {
    'char': ('char', 1),
    'int8_t': ('std::int8_t', 1),
    'uint8_t': ('std::uint8_t', 1),
    'uint8_t_mavlink_version': ('std::uint8_t', 1),
    'int16_t': ('std::int16_t', 2),
    'uint16_t': ('std::uint16_t', 2),
    'int32_t': ('std::int32_t', 4),
    'uint32_t': ('std::uint32_t', 4),
    'float': ('float', 4),
    'int64_t': ('std::int64_t', 8),
    'uint64_t': ('std::uint64_t', 8),
    'double': ('double', 8),
}


class Field:
    def __init__(self, elem, is_extension):
        self.name = elem.get('name')
        raw_type = elem.get('type')
        m = re.fullmatch(r'([a-z0-9_]+)\[(\d+)\]', raw_type)
        if m:
            self.base_type, self.array_len = m.group(1), int(m.group(2))
        else:
            self.base_type, self.array_len = raw_type, 0
        if self.base_type not in TYPES:
            raise SystemExit(f'unknown field type {raw_type!r} in field {self.name}')
        self.cpp_type, self.elem_size = TYPES[self.base_type]
        self.is_extension = is_extension
        self.enum = elem.get('enum')
        self.units = elem.get('units')
        self.offset = 0

    @property
    def wire_size(self):
        return self.elem_size * max(1, self.array_len)

    @property
    def crc_type(self):
        # the mavlink_version pseudo-type hashes as plain uint8_t
        return 'uint8_t' if self.base_type == 'uint8_t_mavlink_version' else self.base_type


class Message:
    def __init__(self, elem, source):
        self.id = int(elem.get('id'))
        self.name = elem.get('name')
        self.source = source
        desc = elem.find('description')
        self.description = ' '.join((desc.text or '').split()) if desc is not None else ''
        fields = []
        in_ext = False
        for child in elem:
            if child.tag == 'extensions':
                in_ext = True
            elif child.tag == 'field':
                fields.append(Field(child, in_ext))
        base = [f for f in fields if not f.is_extension]
        ext = [f for f in fields if f.is_extension]
        # sorted() is stable: equal-size fields keep their XML order
        self.fields = sorted(base, key=lambda f: -f.elem_size) + ext
        offset = 0
        for f in self.fields:
            f.offset = offset
            offset += f.wire_size
        self.min_len = sum(f.wire_size for f in base)
        self.max_len = offset
        self.crc_extra = compute_crc_extra(self.name, [f for f in self.fields if not f.is_extension])


class Enum:
    def __init__(self, name):
        self.name = name
        self.entries = []  # (name, value)
        self.bitmask = False


def crc_accumulate(byte, crc):
    tmp = byte ^ (crc & 0xFF)
    tmp = (tmp ^ (tmp << 4)) & 0xFF
    return ((crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4)) & 0xFFFF


def crc_bytes(data, crc=0xFFFF):
    for b in data:
        crc = crc_accumulate(b, crc)
    return crc


def compute_crc_extra(name, base_fields):
    crc = crc_bytes((name + ' ').encode())
    for f in base_fields:
        crc = crc_bytes((f.crc_type + ' ').encode(), crc)
        crc = crc_bytes((f.name + ' ').encode(), crc)
        if f.array_len:
            crc = crc_accumulate(f.array_len, crc)
    return (crc & 0xFF) ^ (crc >> 8)


def load_dialect(path):
    """Reads the XML and everything it includes (each file once); returns (messages by id, enums by name)."""
    messages, enums, seen = {}, {}, set()

    def load(p):
        p = os.path.realpath(p)
        if p in seen:
            return
        seen.add(p)
        root = ET.parse(p).getroot()
        for inc in root.findall('include'):
            load(os.path.join(os.path.dirname(p), inc.text.strip()))
        for e in root.iter('enum'):
            en = enums.setdefault(e.get('name'), Enum(e.get('name')))
            en.bitmask = en.bitmask or e.get('bitmask') == 'true'
            known = {n for n, _ in en.entries}
            next_value = (max(v for _, v in en.entries) + 1) if en.entries else 0
            for entry in e.findall('entry'):
                value = int(entry.get('value'), 0) if entry.get('value') is not None else next_value
                next_value = value + 1
                if entry.get('name') not in known:
                    en.entries.append((entry.get('name'), value))
                    known.add(entry.get('name'))
        for m in root.iter('message'):
            msg = Message(m, os.path.basename(p))
            if msg.id in messages and messages[msg.id].name != msg.name:
                raise SystemExit(f'message id {msg.id} defined as {messages[msg.id].name} and {msg.name}')
            messages[msg.id] = msg

    load(path)
    return messages, enums


def pascal(name):
    out = ''
    for w in (w for w in name.split('_') if w):
        # keep the separator between two numbers (CR_7_5_M -> Cr7_5M, not Cr75M)
        if out[-1:].isdigit() and w[0].isdigit():
            out += '_'
        out += w[:1].upper() + w[1:].lower()
    return out


def short_names(en):
    """Each entry without the enum's own name prefix, in the XML's spelling (MAV_CMD_NAV_TAKEOFF -> NAV_TAKEOFF,
    MAV_MISSION_ACCEPTED of MAV_MISSION_RESULT -> ACCEPTED); keeps a word more when the rest would start with a
    digit, and the full name when that would collide."""
    enum_words = en.name.split('_')
    names = []
    for entry, _ in en.entries:
        words = entry.split('_')
        common = 0
        while common < min(len(words) - 1, len(enum_words)) and words[common] == enum_words[common]:
            common += 1
        while common > 0 and (words[common][:1].isdigit()):
            common -= 1
        names.append('_'.join(words[common:]))
    idents = [pascal(n) for n in names]
    if len(set(idents)) != len(idents) or any(n[:1].isdigit() for n in idents):
        names = [e for e, _ in en.entries]
    return names


def enumerator_names(en):
    """The C++ enumerators: the short names in PascalCase (MAV_CMD_NAV_TAKEOFF -> NavTakeoff)."""
    names = [pascal(n) for n in short_names(en)]
    if len(set(names)) != len(names):
        raise SystemExit(f'enum {en.name}: enumerator names collide')
    return names


def c_comment(text, limit=110):
    text = text.replace('*/', '* /')
    return text if len(text) <= limit else text[:limit - 3].rstrip() + '...'


def header_banner(xml_path):
    return (
        '// GENERATED by common/generator/mavgen.py from the MAVLink dialect '
        f'{os.path.basename(xml_path)} (with its includes). Do not edit.\n'
        '// Regenerate from the repository root with:\n'
        '//   python3 common/generator/mavgen.py --xml <path/to/definitions>/ardupilotmega.xml\n'
        '// (defaults: --out common --messages common/generator/messages.txt)\n')


def write_enums(inc_dir, xml_path, enums):
    lines = [header_banner(xml_path), '#pragma once', '', '#include <cstdint>', '#include <initializer_list>',
             '#include <type_traits>', '',
             'namespace uavsim::common::mavlink {', '',
             '// The integer value of an enumerator, for writing it into a message field.',
             'template <class E>',
             'constexpr std::underlying_type_t<E> to_underlying(E e) {',
             '  return static_cast<std::underlying_type_t<E>>(e);', '}', '',
             '// Whether a number read from a message field is one of these enumerators (any value is allowed,',
             '// so a number outside the enum is simply none of them).',
             'template <class E, class V>',
             'constexpr bool is_one_of(V value, std::initializer_list<E> any_of) {',
             '  static_assert(std::is_integral_v<V>);',
             '  if constexpr (std::is_signed_v<V>) {',
             '    if (value < 0) return false;',
             '  }',
             '  for (E e : any_of) {',
             '    if (static_cast<std::uint64_t>(value) == static_cast<std::uint64_t>(to_underlying(e))) return true;',
             '  }',
             '  return false;', '}', '']
    for name in sorted(enums):
        en = enums[name]
        if not en.entries:
            continue
        underlying = 'std::uint64_t' if max(v for _, v in en.entries) > 0xFFFFFFFF else 'std::uint32_t'
        lines.append(f'// {en.name}{" (bitmask)" if en.bitmask else ""}')
        lines.append(f'enum class {pascal(en.name)} : {underlying} {{')
        for ident, (entry, value) in zip(enumerator_names(en), en.entries):
            lines.append(f'  {ident} = {value},  // {entry}')
        lines.append('};')
        lines.append('')
    lines.append('}  // namespace uavsim::common::mavlink')
    write(os.path.join(inc_dir, 'enums.hpp'), lines)


def write_enum_names(inc_dir, src_dir, xml_path, enums):
    """enum_name(E) for every enum: the short name of a value (the one programs print: "NAV_TAKEOFF",
    "DENIED"), so no client writes these tables by hand. Where two entries share a value, the first in
    the XML names it."""
    listed = [enums[n] for n in sorted(enums) if enums[n].entries]
    hpp = [header_banner(xml_path), '#pragma once', '', '#include <string_view>', '',
           '#include "uavsim/common/mavlink/generated/enums.hpp"', '',
           'namespace uavsim::common::mavlink {', '',
           '// The entry name of a value without the enum\'s prefix, as the dialect spells it (MavCmd::NavTakeoff',
           '// -> "NAV_TAKEOFF", MavResult::Denied -> "DENIED"); empty for a number that is no entry. The names',
           '// are string literals, so data() is null-terminated. Thread-safe.']
    for en in listed:
        hpp.append(f'std::string_view enum_name({pascal(en.name)} value);')
    hpp += ['', '}  // namespace uavsim::common::mavlink']
    write(os.path.join(inc_dir, 'enum_names.hpp'), hpp)
    cpp = [header_banner(xml_path), '#include "uavsim/common/mavlink/generated/enum_names.hpp"', '',
           'namespace uavsim::common::mavlink {', '']
    for en in listed:
        t = pascal(en.name)
        cpp += [f'std::string_view enum_name({t} value) {{', '  switch (value) {']
        seen = set()
        for ident, short, (_, value) in zip(enumerator_names(en), short_names(en), en.entries):
            if value in seen:
                continue
            seen.add(value)
            cpp.append(f'    case {t}::{ident}: return "{short}";')
        cpp += ['  }', '  return {};', '}', '']
    cpp.append('}  // namespace uavsim::common::mavlink')
    write(os.path.join(src_dir, 'enum_names.cpp'), cpp)


def write_table(inc_dir, src_dir, xml_path, messages):
    hpp = [header_banner(xml_path), '#pragma once', '', '#include <cstdint>', '#include <span>', '',
           'namespace uavsim::common::mavlink {', '',
           '// What the framing layer needs to know about a message id: enough to check the CRC and lengths of',
           '// every message of the dialect, including those without a generated struct.',
           'struct MessageInfo {',
           '  std::uint32_t id;',
           '  std::uint8_t crc_extra;',
           '  std::uint8_t min_len;  // base fields: the MAVLink 1 payload length',
           '  std::uint8_t max_len;  // with extensions: the full MAVLink 2 payload length',
           '  const char* name;',
           '};', '',
           f'inline constexpr std::size_t kMessageCount = {len(messages)};', '',
           '// Returns the entry for a message id, or nullptr when the dialect has no such message. Thread-safe.',
           'const MessageInfo* find_message_info(std::uint32_t id);', '',
           '// All entries, sorted by id. Thread-safe.',
           'std::span<const MessageInfo> all_message_infos();', '',
           '}  // namespace uavsim::common::mavlink']
    write(os.path.join(inc_dir, 'message_table.hpp'), hpp)
    cpp = [header_banner(xml_path), '#include "uavsim/common/mavlink/generated/message_table.hpp"', '',
           '#include <algorithm>', '#include <array>', '',
           'namespace uavsim::common::mavlink {', 'namespace {', '',
           '// sorted by id so lookups can binary-search',
           f'constexpr std::array<MessageInfo, {len(messages)}> kMessageInfos = {{{{']
    for mid in sorted(messages):
        m = messages[mid]
        cpp.append(f'    {{{m.id}, {m.crc_extra}, {m.min_len}, {m.max_len}, "{m.name}"}},')
    cpp += ['}};', '', '}  // namespace', '',
            'const MessageInfo* find_message_info(std::uint32_t id) {',
            '  auto it = std::lower_bound(kMessageInfos.begin(), kMessageInfos.end(), id,',
            '                             [](const MessageInfo& m, std::uint32_t v) { return m.id < v; });',
            '  return (it != kMessageInfos.end() && it->id == id) ? &*it : nullptr;', '}', '',
            'std::span<const MessageInfo> all_message_infos() { return kMessageInfos; }', '',
            '}  // namespace uavsim::common::mavlink']
    write(os.path.join(src_dir, 'message_table.cpp'), cpp)


def member_type(f):
    return f'std::array<{f.cpp_type}, {f.array_len}>' if f.array_len else f.cpp_type


def write_messages(inc_dir, src_dir, xml_path, selected):
    hpp = [header_banner(xml_path), '#pragma once', '', '#include <array>', '#include <cstdint>', '#include <tuple>',
           '',
           'namespace uavsim::common::mavlink::msg {', '',
           '// Each struct holds one message with its fields in wire order. encode() writes the full kMaxLen-byte',
           '// payload (the framing layer truncates it); decode() reads kMaxLen bytes, so a short MAVLink 2',
           '// payload must be zero-filled first (the Parser does this). Both are little-endian, like the wire.',
           '']
    cpp = [header_banner(xml_path), '#include "uavsim/common/mavlink/generated/messages.hpp"', '',
           '#include "uavsim/common/mavlink/wire.hpp"', '',
           'namespace uavsim::common::mavlink::msg {', '']
    for m in selected:
        sname = pascal(m.name)
        if m.description:
            hpp.append(f'// {c_comment(m.description)}')
        hpp += [f'struct {sname} {{',
                f'  static constexpr std::uint32_t kId = {m.id};',
                f'  static constexpr std::uint8_t kCrcExtra = {m.crc_extra};',
                f'  static constexpr std::uint8_t kMinLen = {m.min_len};',
                f'  static constexpr std::uint8_t kMaxLen = {m.max_len};',
                f'  static constexpr const char* kName = "{m.name}";', '']
        for f in m.fields:
            notes = []
            if f.base_type == 'uint8_t_mavlink_version':
                notes.append('MAVLink protocol version, always 3')
            if f.enum:
                notes.append(f.enum)
            if f.units:
                notes.append(f.units)
            if f.is_extension:
                notes.append('extension')
            default = '3' if f.base_type == 'uint8_t_mavlink_version' else ('{}' if f.array_len else '0')
            comment = f'  // {", ".join(notes)}' if notes else ''
            hpp.append(f'  {member_type(f)} {f.name} = {default};{comment}')
        hpp += ['',
                '  void encode(std::uint8_t* payload) const;',
                f'  static {sname} decode(const std::uint8_t* payload);',
                '};', '']
        enc = [f'void {sname}::encode(std::uint8_t* p) const {{']
        dec = [f'{sname} {sname}::decode(const std::uint8_t* p) {{', f'  {sname} m;']
        for f in m.fields:
            enc.append(f'  wire::put(p + {f.offset}, {f.name});')
            dec.append(f'  wire::get(p + {f.offset}, m.{f.name});')
        enc.append('}')
        dec += ['  return m;', '}']
        cpp += enc + [''] + dec + ['']
    hpp.append('// Every generated message type, for code that dispatches on kId or tests all of them.')
    hpp.append('using AllMessages = std::tuple<')
    hpp += [f'    {pascal(m.name)}{"," if i + 1 < len(selected) else ">;"}' for i, m in enumerate(selected)]
    hpp.append('')
    hpp.append('}  // namespace uavsim::common::mavlink::msg')
    cpp.append('}  // namespace uavsim::common::mavlink::msg')
    write(os.path.join(inc_dir, 'messages.hpp'), hpp)
    write(os.path.join(src_dir, 'messages.cpp'), cpp)


def write(path, lines):
    with open(path, 'w', newline='\n') as fh:
        fh.write('\n'.join(lines).rstrip('\n') + '\n')


# CRC_EXTRA values stated by the MAVLink documentation, checked on every run
SELFTEST_CRC_EXTRA = {'HEARTBEAT': 50, 'SYS_STATUS': 124, 'ATTITUDE': 39, 'GLOBAL_POSITION_INT': 104,
                      'COMMAND_LONG': 152}


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--xml', required=True, help='dialect XML, e.g. definitions/ardupilotmega.xml')
    ap.add_argument('--out', default=os.path.join(here, '..'), help='the common/ directory')
    ap.add_argument('--messages', default=os.path.join(here, 'messages.txt'),
                    help='file listing the messages to generate structs for')
    ap.add_argument('--all', action='store_true', help='generate structs for every message of the dialect')
    args = ap.parse_args()

    messages, enums = load_dialect(args.xml)
    by_name = {m.name: m for m in messages.values()}
    for name, crc in SELFTEST_CRC_EXTRA.items():
        if by_name[name].crc_extra != crc:
            raise SystemExit(f'selftest: CRC_EXTRA of {name} is {by_name[name].crc_extra}, expected {crc}')
    if args.all:
        selected = [messages[i] for i in sorted(messages)]
    else:
        with open(args.messages) as fh:
            names = [ln.split('#')[0].strip() for ln in fh]
        names = [n for n in names if n]
        missing = [n for n in names if n not in by_name]
        if missing:
            raise SystemExit(f'messages not in the dialect: {", ".join(missing)}')
        selected = sorted({by_name[n].id: by_name[n] for n in names}.values(), key=lambda m: m.id)

    inc_dir = os.path.join(args.out, 'include', 'uavsim', 'common', 'mavlink', 'generated')
    src_dir = os.path.join(args.out, 'src', 'mavlink', 'generated')
    os.makedirs(inc_dir, exist_ok=True)
    os.makedirs(src_dir, exist_ok=True)
    write_enums(inc_dir, args.xml, enums)
    write_enum_names(inc_dir, src_dir, args.xml, enums)
    write_table(inc_dir, src_dir, args.xml, messages)
    write_messages(inc_dir, src_dir, args.xml, selected)
    print(f'{len(messages)} messages in the table, {len(selected)} structs, '
          f'{sum(1 for e in enums.values() if e.entries)} enums -> {os.path.normpath(args.out)}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
