#!/usr/bin/env python3
"""Checks what lcm-spy showed and decoded against every cblox LCM type (the lcm-spy test).

Usage: check_lcm_spy_table.py LCM_DIR EXPECTED TABLE DECODED

LCM_DIR   lcmtypes/ (parsed with lcmtypes/lcm_schema.py, the parser the build uses)
EXPECTED  "CHANNEL TYPE" per line (publish_lcm_samples --list)
TABLE     lcm-spy's channel table as drawn, tab-separated, header first (lcm_spy_probe)
DECODED   "CHANNEL<TAB>class<TAB>classes in the decoded object tree" (lcm_spy_probe)

Passes (exit 0) when
  * every top-level type (one that no other type contains) is published on some channel,
    and every published type is a cblox type;
  * for every published channel, lcm-spy's table shows the type's name in the Type column
    (lcm-spy looks the message's fingerprint up in the classes of the jars on CLASSPATH and
    shows "?? <fingerprint>" when none matches), at least one message and 0 in Undecodable
    (lcm-spy decodes every message it receives with the class's constructor and counts
    any exception there);
  * the object lcm-spy decoded last on the channel is of class cblox.TYPE and holds an
    object of every cblox type that TYPE contains (transitively, e.g. stereo_pair_t ->
    image_t, camera_calibration_t, pose_t): so every nested type was decoded as well, and
    over all channels every type in LCM_DIR was decoded.
Otherwise it prints each failure and exits 1.
"""

import os
import sys


def load_schema(lcm_dir):
    sys.dont_write_bytecode = True  # no __pycache__ in the source tree
    sys.path.insert(0, lcm_dir)
    import lcm_schema  # noqa: E402 (lcmtypes/lcm_schema.py)

    structs = []
    package = None
    for f in sorted(os.listdir(lcm_dir)):
        if not f.endswith(".lcm"):
            continue
        path = os.path.join(lcm_dir, f)
        with open(path, encoding="utf-8") as stream:
            package, file_structs = lcm_schema.Parser(
                path, lcm_schema.tokenize(path, stream.read())).parse_file()
        structs += file_structs
    by_name = lcm_schema.resolve(package, structs)
    contains = {name: {m.struct_type for m in s.members if m.struct_type}
                for name, s in by_name.items()}
    return package, contains


def closure(contains, name):
    seen, todo = set(), [name]
    while todo:
        for child in contains[todo.pop()]:
            if child not in seen:
                seen.add(child)
                todo.append(child)
    return seen


def read_tsv(path):
    with open(path, encoding="utf-8") as stream:
        return [line.rstrip("\n").split("\t") for line in stream if line.strip()]


def main(argv):
    if len(argv) != 5:
        print(__doc__, file=sys.stderr)
        return 2
    lcm_dir, expected_path, table_path, decoded_path = argv[1:]
    package, contains = load_schema(lcm_dir)
    all_types = set(contains)
    nested = set().union(*contains.values())
    top_level = all_types - nested
    failures = []

    expected = []
    with open(expected_path, encoding="utf-8") as stream:
        for line in stream:
            if line.strip():
                channel, type_name = line.split()
                expected.append((channel, type_name))
    published = {t for _, t in expected}
    for t in sorted(published - all_types):
        failures.append(f"published type {t} is not a type of {lcm_dir}")
    for t in sorted(top_level - published):
        failures.append(f"top-level type {t} is published on no channel "
                        "(add it to test/daemon/publish_lcm_samples.cc)")

    table = read_tsv(table_path)
    header, rows = table[0], table[1:]
    columns = {}
    for name in ("Channel", "Type", "Num Msgs", "Undecodable"):
        if name not in header:
            failures.append(f"lcm-spy's table has no column '{name}' (columns: {header})")
        columns[name] = header.index(name) if name in header else None
    shown = {}
    if None not in columns.values():
        shown = {r[columns["Channel"]]: r for r in rows}

    decoded = {}
    for r in read_tsv(decoded_path):
        if r[0] == "ERROR":
            failures.append(" ".join(r[1:]))
            continue
        decoded[r[0]] = (r[1], set(r[2].split(",")) if len(r) > 2 and r[2] else set())

    seen_classes = set()
    print(f"{'channel':<22} {'type':<24} {'lcm-spy Type':<24} {'msgs':>5} {'undec':>5}  decoded classes")
    for channel, type_name in expected:
        row = shown.get(channel)
        cls, classes = decoded.get(channel, ("-", set()))
        seen_classes |= classes
        if row is None:
            print(f"{channel:<22} {type_name:<24} (not in lcm-spy's table)")
            failures.append(f"{channel}: not in lcm-spy's table")
            continue
        spy_type = row[columns["Type"]]
        msgs, undecodable = row[columns["Num Msgs"]], row[columns["Undecodable"]]
        print(f"{channel:<22} {type_name:<24} {spy_type:<24} {msgs:>5} {undecodable:>5}  "
              f"{','.join(sorted(c.rsplit('.', 1)[-1] for c in classes))}")
        if spy_type != type_name:
            failures.append(f"{channel}: lcm-spy shows type '{spy_type}', expected '{type_name}'"
                            " (the jar on CLASSPATH lacks the type or has another version)")
        if not msgs.isdigit() or int(msgs) < 1:
            failures.append(f"{channel}: lcm-spy counted '{msgs}' messages")
        if undecodable != "0":
            failures.append(f"{channel}: lcm-spy could not decode {undecodable} messages")
        want = {f"{package}.{t}" for t in {type_name} | closure(contains, type_name)}
        if cls != f"{package}.{type_name}":
            failures.append(f"{channel}: lcm-spy decoded with class '{cls}', expected "
                            f"'{package}.{type_name}'")
        missing = want - classes
        if missing and cls == f"{package}.{type_name}":
            failures.append(f"{channel}: lcm-spy's decoded {type_name} holds no "
                            f"{', '.join(sorted(missing))} object")
    for channel, row in sorted(shown.items()):
        if channel not in dict(expected):
            print(f"(also in lcm-spy's table: {' | '.join(row)})")

    never = {f"{package}.{t}" for t in all_types} - seen_classes
    for c in sorted(never):
        failures.append(f"type {c} was decoded on no channel")

    if failures:
        print(f"FAIL: {len(failures)} problem(s):")
        for f in failures:
            print(f"  {f}")
        return 1
    print(f"OK: lcm-spy decoded all {len(all_types)} cblox types: {len(top_level)} top-level "
          f"types on {len(expected)} channels, {len(nested)} nested types inside them")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
