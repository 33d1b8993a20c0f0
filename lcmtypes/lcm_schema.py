#!/usr/bin/env python3
"""Writes cblox/wire_schema.hpp: the wire layout of every LCM struct of a folder.

Usage: lcm_schema.py LCM_DIR OUTPUT_HEADER

Parses every LCM_DIR/*.lcm (the grammar lcm-gen accepts, minus enums and types of other
packages: `package`, `struct NAME { ... }`, `//` and `/* */` comments, `const TYPE A = 1,
B = 2;`, members `TYPE a, b[DIM][DIM2];` with DIM an integer literal or an earlier scalar
integer member) and writes a C++ header describing each struct for lcmtypes/wire_check.cc:
its members in wire order, their kind, the minimum encoded size of one element and their
array dimensions (a literal or the index of the count member). Any grammar it does not
understand, an unknown type or a recursive type is an error: the message names the file and
line, nothing is written and the exit status is 1 (so the build fails).
Python 3 standard library only.
"""

import os
import re
import sys
import tempfile
from dataclasses import dataclass, field

# Primitive LCM types: (wire_schema::Kind, minimum encoded bytes of one element). A string
# is an int32 length (counting the NUL) followed by the bytes and the NUL: at least 5.
PRIMITIVES = {
    "int8_t": ("kInt8", 1), "int16_t": ("kInt16", 2), "int32_t": ("kInt32", 4),
    "int64_t": ("kInt64", 8), "byte": ("kByte", 1), "boolean": ("kBoolean", 1),
    "float": ("kFloat", 4), "double": ("kDouble", 8), "string": ("kString", 5),
}
COUNT_TYPES = {"int8_t", "int16_t", "int32_t", "int64_t"}  # may hold an array length
CONST_TYPES = COUNT_TYPES | {"float", "double"}

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"
TOKEN_RE = re.compile(r"""
    (?P<newline>\n) | (?P<space>[ \t\r\f\v]+) | (?P<line_comment>//[^\n]*)
  | (?P<block_comment>/\*.*?\*/)
  | (?P<word>{0}(?:\.{0})*)
  | (?P<number>[-+]?(?:0[xX][0-9a-fA-F]+|(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?))
  | (?P<punct>[{{}}\[\];,=])
""".format(IDENT), re.VERBOSE | re.DOTALL)


class SchemaError(Exception):
    pass


@dataclass
class Member:
    name: str
    type: str                 # as written, e.g. "int32_t", "pose_t", "cblox.pose_t"
    dims: list                # int (literal) or str (name of the count member)
    where: str                # "file:line" for messages
    struct_type: str = ""     # resolved struct name for non-primitive members


@dataclass
class Struct:
    name: str
    where: str
    members: list = field(default_factory=list)
    min_size: int = -1        # minimum encoded size without fingerprint (after resolve)


def tokenize(path, text):
    """Returns [(token, line)], comments and whitespace dropped."""
    tokens, line, pos = [], 1, 0
    while pos < len(text):
        m = TOKEN_RE.match(text, pos)
        if not m:
            what = "unterminated /* comment" if text.startswith("/*", pos) else \
                f"unexpected character {text[pos]!r}"
            raise SchemaError(f"{path}:{line}: {what}")
        kind = m.lastgroup
        if kind not in ("newline", "space", "line_comment", "block_comment"):
            tokens.append((m.group(), line))
        line += m.group().count("\n")
        pos = m.end()
    return tokens


class Parser:
    """Recursive descent over one file's tokens."""

    def __init__(self, path, tokens):
        self.path, self.tokens, self.i = path, tokens, 0

    def where(self):
        line = self.tokens[min(self.i, len(self.tokens) - 1)][1] if self.tokens else 1
        return f"{self.path}:{line}"

    def error(self, message):
        raise SchemaError(f"{self.where()}: {message}")

    def peek(self):
        return self.tokens[self.i][0] if self.i < len(self.tokens) else None

    def next(self, what):
        tok = self.peek()
        if tok is None:
            self.error(f"unexpected end of file, expected {what}")
        self.i += 1
        return tok

    def expect(self, token):
        tok = self.next(f"'{token}'")
        if tok != token:
            self.i -= 1
            self.error(f"expected '{token}', got '{tok}'")

    def name(self, what):
        tok = self.next(what)
        if not re.fullmatch(IDENT, tok):
            self.i -= 1
            self.error(f"expected {what}, got '{tok}'")
        return tok

    def parse_file(self):
        """Returns (package or None, [Struct])."""
        package, structs = None, []
        while self.peek() is not None:
            tok = self.next("'package' or 'struct'")
            if tok == "package":
                if package is not None or structs:
                    self.error("'package' must come once, before the structs")
                package = self.next("package name")
                if not re.fullmatch(rf"{IDENT}(?:\.{IDENT})*", package):
                    self.error(f"invalid package name '{package}'")
                self.expect(";")
            elif tok == "struct":
                structs.append(self.parse_struct())
            elif tok == "enum":
                self.error("LCM enums are not supported (use an int constant in a struct)")
            else:
                self.i -= 1
                self.error(f"expected 'package' or 'struct', got '{tok}'")
        return package, structs

    def parse_struct(self):
        s = Struct(self.name("struct name"), self.where())
        self.expect("{")
        taken = set()
        while self.peek() != "}":
            if self.peek() in ("struct", "enum"):
                self.error("nested struct/enum declarations are not supported")
            if self.peek() == "const":
                self.i += 1
                self.parse_const(taken)
            else:
                self.parse_members(s, taken)
        self.expect("}")
        return s

    def parse_const(self, taken):
        ctype = self.next("constant type")
        if ctype not in CONST_TYPES:
            self.i -= 1
            self.error(f"constant type must be one of {sorted(CONST_TYPES)}, got '{ctype}'")
        while True:
            self.declare(self.name("constant name"), taken)
            self.expect("=")
            value = self.next("constant value")
            number = r"[-+]?(?:0[xX][0-9a-fA-F]+|\d+)" if ctype in COUNT_TYPES else \
                r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
            if not re.fullmatch(number, value):
                self.i -= 1
                self.error(f"invalid {ctype} constant value '{value}'")
            if self.end_of_declaration():
                return

    def parse_members(self, s, taken):
        mtype = self.next("member type")
        if not re.fullmatch(rf"{IDENT}(?:\.{IDENT})*", mtype):
            self.i -= 1
            self.error(f"expected a member type, got '{mtype}'")
        while True:
            where = self.where()
            m = Member(self.declare(self.name("member name"), taken), mtype, [], where)
            while self.peek() == "[":
                self.i += 1
                m.dims.append(self.parse_dim(s))
                self.expect("]")
            s.members.append(m)
            if self.end_of_declaration():
                return

    def parse_dim(self, s):
        tok = self.next("array dimension")
        if re.fullmatch(r"[1-9]\d*|0[xX][0-9a-fA-F]+", tok):
            if int(tok, 0) <= 0:
                self.i -= 1
                self.error("constant array dimension must be > 0")
            return int(tok, 0)
        count = next((m for m in s.members if m.name == tok), None)
        if count is None or count.dims or count.type not in COUNT_TYPES:
            self.i -= 1
            self.error(f"array dimension '{tok}' must be a positive decimal or hex literal or "
                       "an earlier scalar int8_t/int16_t/int32_t/int64_t member")
        return tok

    def end_of_declaration(self):
        """Consumes ';' (True) or ',' (False, another name follows)."""
        tok = self.next("',' or ';'")
        if tok not in (",", ";"):
            self.i -= 1
            self.error(f"expected ',' or ';' after '{self.tokens[self.i - 1][0]}', got '{tok}'")
        return tok == ";"

    def declare(self, name, taken):
        if name in taken:
            self.i -= 1
            self.error(f"duplicate member or constant name '{name}'")
        taken.add(name)
        return name


def resolve(package, structs):
    """Resolves member types, rejects recursion and computes minimum encoded sizes."""
    by_name = {}
    for s in structs:
        if s.name in by_name:
            raise SchemaError(f"{s.where}: struct {s.name} already declared at "
                              f"{by_name[s.name].where}")
        by_name[s.name] = s
    for s in structs:
        for m in s.members:
            if m.type in PRIMITIVES:
                continue
            pkg, _, short = m.type.rpartition(".")
            if pkg and pkg != package:
                raise SchemaError(f"{m.where}: type '{m.type}' is from another package "
                                  f"(only package {package} is supported)")
            if short not in by_name:
                raise SchemaError(f"{m.where}: unknown type '{m.type}' (no struct {short} in "
                                  "the .lcm files)")
            m.struct_type = short

    def min_size(s, stack):
        if s.min_size >= 0:
            return s.min_size
        if s.name in stack:
            raise SchemaError(f"{s.where}: recursive type {' -> '.join(stack + [s.name])} is not "
                              "supported")
        total = 0
        for m in s.members:
            elem = PRIMITIVES[m.type][1] if m.type in PRIMITIVES else \
                min_size(by_name[m.struct_type], stack + [s.name])
            if all(isinstance(d, int) for d in m.dims):  # a variable dimension may be 0
                for d in m.dims:
                    elem *= d
                total += elem
        s.min_size = total
        return total

    for s in structs:
        min_size(s, [])
    return by_name


def render(package, structs, source):
    """Returns the header text; structs sorted by name."""
    index = {s.name: i for i, s in enumerate(structs)}
    struct_rows, field_rows, dim_rows, n_fields = [], [], [], 0
    for s in structs:
        struct_rows.append(f'    {{"{s.name}", {n_fields}, {len(s.members)}, {s.min_size}}},')
        field_rows.append(f"    // {s.name}: kFields[{n_fields}, {n_fields + len(s.members)})")
        local = {m.name: i for i, m in enumerate(s.members)}
        for m in s.members:
            if m.type in PRIMITIVES:
                (kind, elem), sub = PRIMITIVES[m.type], -1
            else:
                sub = index[m.struct_type]
                kind, elem = "kStruct", structs[sub].min_size
            field_rows.append(f'    {{"{m.name}", Kind::{kind}, {elem}, {sub}, '
                              f'{len(dim_rows) if m.dims else 0}, {len(m.dims)}}},')
            for d in m.dims:
                dim_rows.append(f"    {{{d}, -1}}," if isinstance(d, int) else
                                f"    {{-1, {local[d]}}},  // {s.name}.{d}")
        n_fields += len(s.members)
    max_fields = max((len(s.members) for s in structs), default=0)
    max_dims = max((len(m.dims) for s in structs for m in s.members), default=0)
    namespace = package.replace(".", "::")

    def table(ctype, name, rows, count):
        if not count:
            return f"inline constexpr std::array<{ctype}, 0> {name} = {{}};"
        body = "\n".join(rows)
        return f"inline constexpr std::array<{ctype}, {count}> {name} = {{{{\n{body}\n}}}};"

    for_each = " \\\n".join(f"  X({s.name})" for s in structs)
    return f"""\
// Generated by lcmtypes/lcm_schema.py from the {len(structs)} structs of {source}/*.lcm.
// DO NOT EDIT. The wire layout of every LCM type of package {package}, read by
// lcmtypes/wire_check.cc to bound lengths before decoding. All tables are constexpr
// (thread-safe, no initialisation order).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

namespace {namespace}::wire_schema {{

/// How one element of a member is encoded.
enum class Kind : uint8_t {{
  kInt8, kInt16, kInt32, kInt64, kByte, kBoolean, kFloat, kDouble,  // big-endian, fixed size
  kString,  // int32 length counting the NUL, then the bytes and the NUL
  kStruct,  // the nested struct's members, without fingerprint
}};

/// One array dimension: a literal `size` (field == -1), or the value of the scalar integer
/// member `field` (index within the same struct, declared earlier; size == -1).
struct Dim {{
  int64_t size;
  int32_t field;
}};

/// One member, in wire order.
struct Field {{
  std::string_view name;
  Kind kind;
  int64_t elem_min_size;  ///< encoded bytes of one element: exact for the fixed-size kinds,
                          ///< a lower bound for kString (5) and kStruct (the struct's min_size)
  int32_t struct_index;   ///< index in kStructs for kStruct, else -1
  int32_t first_dim;      ///< dimensions are kDims[first_dim, first_dim + num_dims)
  int32_t num_dims;       ///< 0 for a scalar
}};

/// One struct: its members are kFields[first_field, first_field + num_fields).
struct Struct {{
  std::string_view name;  ///< without package, e.g. "keyframe_t"
  int32_t first_field;
  int32_t num_fields;
  int64_t min_size;       ///< minimum encoded size without fingerprint
}};

inline constexpr std::string_view kPackage = "{package}";
/// Most members of any one struct.
inline constexpr int kMaxFields = {max_fields};
/// Most dimensions of any one member.
inline constexpr int kMaxDims = {max_dims};

/// Sorted by name.
{table("Struct", "kStructs", struct_rows, len(structs))}

{table("Field", "kFields", field_rows, n_fields)}

{table("Dim", "kDims", dim_rows, len(dim_rows))}

}}  // namespace {namespace}::wire_schema

/// X-macro over every struct name (sorted), e.g. to make a test cover every type.
#define CBLOX_WIRE_SCHEMA_FOR_EACH_TYPE(X) \\
{for_each}
"""


def main(argv):
    if len(argv) != 3:
        print(f"usage: {argv[0]} LCM_DIR OUTPUT_HEADER", file=sys.stderr)
        return 2
    lcm_dir, output = argv[1], argv[2]
    try:
        files = sorted(f for f in os.listdir(lcm_dir) if f.endswith(".lcm"))
        if not files:
            raise SchemaError(f"no .lcm files in {lcm_dir}")
        packages, structs = {}, []
        for f in files:
            path = os.path.join(lcm_dir, f)
            with open(path, encoding="utf-8") as stream:
                package, file_structs = Parser(path, tokenize(path, stream.read())).parse_file()
            if package is None:
                raise SchemaError(f"{path}: no 'package' declaration")
            if not file_structs:
                raise SchemaError(f"{path}: no struct")
            packages.setdefault(package, f)
            structs += file_structs
        if len(packages) != 1:
            raise SchemaError("all .lcm files must share one package, found " +
                              ", ".join(f"{p} ({f})" for p, f in sorted(packages.items())))
        package = next(iter(packages))
        resolve(package, structs)
        text = render(package, sorted(structs, key=lambda s: s.name),
                      os.path.basename(os.path.abspath(lcm_dir)))
    except (SchemaError, OSError, UnicodeDecodeError) as e:
        print(f"lcm_schema.py: error: {e}", file=sys.stderr)
        return 1
    # Atomic replace: a failed or interrupted run never leaves a partial header behind.
    os.makedirs(os.path.dirname(os.path.abspath(output)), exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(os.path.abspath(output)), suffix=".tmp")
    with os.fdopen(fd, "w", encoding="utf-8") as stream:
        stream.write(text)
    os.replace(tmp, output)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
