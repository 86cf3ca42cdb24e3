#!/usr/bin/env python3
"""Generates python/sketchbody/_bindings.py (the ctypes declarations of every skb_* function,
struct, constant and status code) from include/sketchbody.h.

    python3 python/tools/gen_bindings.py            # rewrite python/sketchbody/_bindings.py
    python3 python/tools/gen_bindings.py --check    # exit 1 when the committed file is stale

The header is cbindgen's output (scripts/gen-header.sh), so its shape is regular: doc comments
`/** ... */`, `#define NAME <integer>` or `<decimal>`, one `enum skb_status`, opaque `typedef struct X X;`,
plain structs `typedef struct X { ... } X;`, one callback typedef and the prototypes inside
`extern "C" { ... }`. Anything the parser does not recognise is an error, so a new kind of
declaration in the header fails here instead of being skipped silently.
python/tests/test_bindings.py regenerates and diffs, compares the exports of the built library
with the declarations and compiles a C program that checks every struct layout, constant and
prototype against the real header.

Standard library only.
"""

import argparse
import hashlib
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
HEADER = os.path.join(ROOT, "include", "sketchbody.h")
OUTPUT = os.path.join(ROOT, "python", "sketchbody", "_bindings.py")

# C scalar type -> ctypes name. Pointers to these become POINTER(...); `char *` and `void *`
# are special-cased in ctype_of.
SCALARS = {
    "bool": "ctypes.c_bool",
    "char": "ctypes.c_char",
    "int": "ctypes.c_int",
    "float": "ctypes.c_float",
    "double": "ctypes.c_double",
    "size_t": "ctypes.c_size_t",
    "uint8_t": "ctypes.c_uint8",
    "int32_t": "ctypes.c_int32",
    "uint32_t": "ctypes.c_uint32",
    "uint64_t": "ctypes.c_uint64",
    "skb_status": "ctypes.c_uint32",
}


class HeaderError(Exception):
    pass


def clean_doc(block):
    """The text of a `/** ... */` comment, one string, lines joined with newlines."""
    body = block.strip()[3:-2]
    lines = []
    for line in body.splitlines():
        line = line.strip()
        if line.startswith("*"):
            line = line[1:]
            if line.startswith(" "):
                line = line[1:]
        lines.append(line.rstrip())
    while lines and not lines[0]:
        lines.pop(0)
    while lines and not lines[-1]:
        lines.pop()
    return "\n".join(lines)


def read_doc(lines, i):
    """The doc comment starting at lines[i] and the index of its last line."""
    block = [lines[i]]
    while "*/" not in lines[i]:
        i += 1
        block.append(lines[i])
    return clean_doc("\n".join(block)), i


def split_decl(text):
    """'const struct skb_image *src' -> ('const struct skb_image *', 'src', dims)."""
    text = " ".join(text.split())
    m = re.fullmatch(r"(.*?)([A-Za-z_]\w*)((?:\[[^\]]+\])*)", text)
    if not m:
        raise HeaderError(f"cannot parse declaration {text!r}")
    ctype, name, dims = m.group(1).strip(), m.group(2), m.group(3)
    ctype = re.sub(r"\s*\*", " *", ctype).replace("* *", "**").strip()
    return ctype, name, re.findall(r"\[([^\]]+)\]", dims)


def base_and_depth(ctype):
    """'const struct skb_image *' -> ('skb_image', 1, True)."""
    depth = ctype.count("*")
    words = ctype.replace("*", " ").split()
    const = "const" in words
    words = [w for w in words if w not in ("const", "struct")]
    if len(words) != 1:
        raise HeaderError(f"unsupported type {ctype!r}")
    return words[0], depth, const


def parse(text):
    """The header's declarations as a dict of lists (see the keys below)."""
    out = {"constants": [], "status": [], "opaque": [], "structs": [], "callbacks": [],
           "functions": [], "joint_names": None}
    lines = text.splitlines()
    i, doc = 0, ""
    in_extern = False

    def take_doc():
        nonlocal doc
        d, doc = doc, ""
        return d

    while i < len(lines):
        line = lines[i].strip()
        if not line or line.startswith("//"):
            i += 1
            continue
        if line.startswith("/**"):
            doc, i = read_doc(lines, i)
            i += 1
            continue
        if line.startswith("/*"):   # the plain banner comment
            while "*/" not in lines[i]:
                i += 1
            i += 1
            doc = ""
            continue
        if line.startswith("#"):
            m = re.fullmatch(r"#define\s+(SKB_\w+)\s+(-?\d+)", line)
            mf = re.fullmatch(r"#define\s+(SKB_\w+)\s+(-?\d+\.\d+)", line)
            if m:
                out["constants"].append((m.group(1), int(m.group(2)), take_doc()))
            elif mf:
                out["constants"].append((mf.group(1), float(mf.group(2)), take_doc()))
            elif re.match(r"#define\s+SKB_(STRINGIFY_?|VERSION_STRING)\b", line) or \
                    re.match(r"#(ifndef|ifdef|endif|include|define SKETCHBODY_H\b)", line):
                doc = "" if line.startswith("#define") else doc
            else:
                raise HeaderError(f"unrecognised preprocessor line: {line}")
            i += 1
            continue
        if line == 'extern "C" {':
            in_extern = True
            i += 1
            continue
        if line.startswith("}") and "extern" in line:
            in_extern = False
            i += 1
            continue
        if line == "enum skb_status":
            enum_doc = take_doc()
            i += 1
            values = []
            while not lines[i].strip().startswith("};"):
                s = lines[i].strip()
                if s.startswith("/**"):
                    doc, i = read_doc(lines, i)
                else:
                    m = re.fullmatch(r"(SKB_\w+)\s*=\s*(\d+),?", s)
                    if m:
                        values.append((m.group(1), int(m.group(2)), take_doc()))
                    elif s not in ("{", ": uint32_t") and not s.startswith("#"):
                        raise HeaderError(f"unrecognised enum line: {s}")
                i += 1
            out["status"] = values
            out["status_doc"] = enum_doc
            i += 1
            continue
        m = re.fullmatch(r"typedef uint32_t skb_status;", line)
        if m:
            i += 1
            continue
        m = re.fullmatch(r"typedef struct (skb_\w+) \1;", line)
        if m:
            out["opaque"].append((m.group(1), take_doc()))
            i += 1
            continue
        m = re.fullmatch(r"typedef struct (skb_\w+) \{", line)
        if m:
            name, sdoc = m.group(1), take_doc()
            fields = []
            i += 1
            while not lines[i].strip().startswith("}"):
                s = lines[i].strip()
                if s.startswith("/**"):
                    doc, i = read_doc(lines, i)
                elif s:
                    if not s.endswith(";"):
                        raise HeaderError(f"unrecognised struct line: {s}")
                    ctype, fname, dims = split_decl(s[:-1])
                    fields.append((fname, ctype, dims, take_doc()))
                i += 1
            if lines[i].strip() != f"}} {name};":
                raise HeaderError(f"unexpected struct end: {lines[i]}")
            out["structs"].append((name, fields, sdoc))
            if name == "skb_joints2d":
                jm = re.search(r"canonical order \(([^)]*)\)", sdoc.replace("\n", " "))
                if not jm:
                    raise HeaderError("skb_joints2d's comment no longer lists the joints")
                out["joint_names"] = [n.strip() for n in jm.group(1).split(",")]
            i += 1
            continue
        m = re.fullmatch(r"typedef (.+?) \(\*(skb_\w+)\)\((.*)\);", line)
        if m:
            params = [split_decl(p)[:2] for p in m.group(3).split(",")]
            out["callbacks"].append((m.group(2), m.group(1).strip(), params, take_doc()))
            i += 1
            continue
        # A prototype, possibly over several lines.
        stmt = line
        while not stmt.endswith(";"):
            i += 1
            stmt += " " + lines[i].strip()
        i += 1
        if not in_extern:
            raise HeaderError(f"declaration outside extern \"C\": {stmt}")
        m = re.fullmatch(r"(.+?)\b(skb_\w+)\((.*)\);", " ".join(stmt.split()))
        if not m:
            raise HeaderError(f"unrecognised declaration: {stmt}")
        ret = re.sub(r"\s*\*", " *", m.group(1).strip())
        params = [] if m.group(3).strip() in ("", "void") else \
            [split_decl(p)[:2] for p in m.group(3).split(",")]
        out["functions"].append((m.group(2), ret, params, take_doc()))
    if out["joint_names"] is None or len(out["joint_names"]) != 15:
        raise HeaderError("joint names not found")
    return out


def ctype_of(ctype, opaque, structs, callbacks, ret=False):
    """The ctypes expression of a C type (as text)."""
    base, depth, _ = base_and_depth(ctype)
    if depth == 0:
        if base == "void" and ret:
            return "None"
        if base in callbacks:
            return base
        if base in SCALARS:
            return SCALARS[base]
        if base in structs:
            return base
        raise HeaderError(f"unsupported value type {ctype!r}")
    if base == "char" and depth == 1:
        # Borrowed static text out; UTF-8 path in; or a caller buffer (POINTER(c_char)).
        return "ctypes.c_char_p" if ret or "const" in ctype.split() else "ctypes.POINTER(ctypes.c_char)"
    if base == "void" and depth == 1:
        return "ctypes.c_void_p"
    if base in SCALARS:
        inner = SCALARS[base]
    elif base in opaque or base in structs:
        inner = base
    else:
        raise HeaderError(f"unsupported pointer type {ctype!r}")
    for _ in range(depth):
        inner = f"ctypes.POINTER({inner})"
    return inner


def comment(doc, indent=""):
    return "".join(f"{indent}# {line}".rstrip() + "\n" for line in doc.splitlines())


def generate(text):
    d = parse(text)
    consts = {n: v for n, v, _ in d["constants"]}
    opaque = {n for n, _ in d["opaque"]}
    structs = {n for n, _, _ in d["structs"]}
    callbacks = {n for n, *_ in d["callbacks"]}
    sha = hashlib.sha256(text.encode()).hexdigest()
    o = []
    w = o.append
    w('"""ctypes declarations of the sketchbody C API.\n\n'
      "GENERATED by python/tools/gen_bindings.py from include/sketchbody.h: do not edit by hand.\n"
      "Regenerate with `python3 python/tools/gen_bindings.py`; python/tests/test_bindings.py fails\n"
      "when this file and the header drift apart. The Pythonic layer is sketchbody/__init__.py;\n"
      "use these only for what it does not wrap. The comments are the header's documentation.\n"
      '"""\n\n')
    w("import ctypes\n\n")
    w(f'HEADER_SHA256 = "{sha}"\n\n')
    w("# ---- constants (#define) ----\n\n")
    for n, v, doc in d["constants"]:
        w(comment(doc))
        w(f"{n} = {v}\n")
    w(f'SKB_VERSION_STRING = "{consts["SKB_VERSION_MAJOR"]}.{consts["SKB_VERSION_MINOR"]}.'
      f'{consts["SKB_VERSION_PATCH"]}"\n\n')
    w("CONSTANTS = {\n")
    for n, v, _ in d["constants"]:
        w(f'    "{n}": {v},\n')
    w("}\n\n")
    w("# The 15 canonical joints, in order (from skb_joints2d's documentation).\n")
    w("JOINT_NAMES = (\n")
    for n in d["joint_names"]:
        w(f'    "{n}",\n')
    w(")\n\n")
    w("# ---- enum skb_status ----\n\n")
    w(comment(d["status_doc"]))
    for n, v, doc in d["status"]:
        w(comment(doc))
        w(f"{n} = {v}\n")
    w("\nSTATUS_NAMES = {\n")
    for n, v, _ in d["status"]:
        w(f'    {v}: "{n}",\n')
    w("}\n\n")
    w("# ---- opaque handles (use through POINTER(...)) ----\n\n")
    for n, doc in d["opaque"]:
        w(comment(doc))
        w(f"class {n}(ctypes.Structure):\n    pass\n\n\n")
    w("# ---- plain structs ----\n\n")
    struct_fields = {}
    for n, fields, doc in d["structs"]:
        w(comment(doc))
        w(f"class {n}(ctypes.Structure):\n    _fields_ = [\n")
        flist = []
        for fname, ctype, dims, fdoc in fields:
            t = ctype_of(ctype, opaque, structs, callbacks)
            for dim in reversed(dims):
                size = int(dim) if dim.isdigit() else consts[dim]
                t = f"({t} * {size})"
            first = fdoc.splitlines()[0] if fdoc else ""
            w(f'        ("{fname}", {t}),  # {first}'.rstrip() + "\n")
            flist.append((fname, ctype + "".join(f"[{x}]" for x in dims)))
        w("    ]\n\n\n")
        struct_fields[n] = flist
    w("# C field types of each struct (the drift test compiles offsetof/sizeof checks from these).\n")
    w("STRUCT_FIELDS = {\n")
    for n, flist in struct_fields.items():
        w(f'    "{n}": (\n')
        for fname, ct in flist:
            w(f'        ("{fname}", "{ct}"),\n')
        w("    ),\n")
    w("}\n\n")
    w("# ---- callbacks ----\n\n")
    for n, ret, params, doc in d["callbacks"]:
        w(comment(doc))
        args = ", ".join(ctype_of(ct, opaque, structs, callbacks) for ct, _ in params)
        w(f"{n} = ctypes.CFUNCTYPE({ctype_of(ret, opaque, structs, callbacks, ret=True)}, {args})\n\n")
    w("# ---- functions ----\n")
    w("# name: (restype, argtypes, C return type, ((argument name, C type), ...))\n\n")
    w("FUNCTIONS = {}\n\n")
    for n, ret, params, doc in d["functions"]:
        w("\n" + comment(doc))
        r = ctype_of(ret, opaque, structs, callbacks, ret=True)
        args = "".join(f"        {ctype_of(ct, opaque, structs, callbacks)},\n" for ct, _ in params)
        cparams = "".join(f'        ("{pn}", "{ct}"),\n' for ct, pn in params)
        w(f'FUNCTIONS["{n}"] = (\n    {r},\n    [\n{args}    ],\n    "{ret}",\n'
          f"    (\n{cparams}    ),\n)\n")
    w('\n\ndef declare(lib):\n'
      '    """Sets restype and argtypes of every skb_* function on the ctypes.CDLL `lib`;\n'
      '    returns the names the library lacks (an older library than the header)."""\n'
      "    missing = []\n"
      "    for name, (restype, argtypes, _, _) in FUNCTIONS.items():\n"
      "        try:\n"
      "            fn = getattr(lib, name)\n"
      "        except AttributeError:\n"
      "            missing.append(name)\n"
      "            continue\n"
      "        fn.restype = restype\n"
      "        fn.argtypes = argtypes\n"
      "    return missing\n")
    return "".join(o)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--header", default=HEADER)
    ap.add_argument("--out", default=OUTPUT)
    ap.add_argument("--check", action="store_true", help="exit 1 if --out differs from a fresh generation")
    a = ap.parse_args()
    with open(a.header, encoding="utf-8") as f:
        text = generate(f.read())
    if a.check:
        try:
            with open(a.out, encoding="utf-8") as f:
                same = f.read() == text
        except FileNotFoundError:
            same = False
        if not same:
            print(f"{a.out} is stale: run python3 python/tools/gen_bindings.py", file=sys.stderr)
            return 1
        return 0
    tmp = a.out + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, a.out)
    print(f"wrote {os.path.relpath(a.out, ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
