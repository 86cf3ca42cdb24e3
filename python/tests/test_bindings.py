"""The ctypes declarations against the header and the built library (the drift test).

1. python/sketchbody/_bindings.py equals a fresh generation from include/sketchbody.h
   (python/tools/gen_bindings.py): any header change not regenerated fails here.
2. The library's exported skb_* symbols (nm -D) are exactly the declared functions.
3. A C program compiled against the real header checks every constant, status value, struct
   size and field offset against the ctypes side, and every recorded prototype against the
   declaration (__builtin_types_compatible_p), so a parser slip cannot go unnoticed.
4. Each scalar C type's size and signedness matches its ctypes type; every argument's pointer
   depth matches its ctypes argtype.
"""

import ctypes
import importlib.util
import os
import shutil
import subprocess
import tempfile
import sys
import unittest

import sketchbody
from sketchbody import _bindings as B

from _util import ROOT

TOOLS = os.path.join(ROOT, "python", "tools", "gen_bindings.py")
HEADER = os.path.join(ROOT, "include", "sketchbody.h")


def load_generator():
    spec = importlib.util.spec_from_file_location("gen_bindings", TOOLS)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


class BindingsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.gen = load_generator()
        with open(HEADER, encoding="utf-8") as f:
            cls.header = f.read()

    def test_generated_file_matches_header(self):
        fresh = self.gen.generate(self.header)
        with open(os.path.join(ROOT, "python", "sketchbody", "_bindings.py"), encoding="utf-8") as f:
            committed = f.read()
        self.assertTrue(fresh == committed, "python/sketchbody/_bindings.py is stale: run "
                        "python3 python/tools/gen_bindings.py")
        # The installed copy (the one imported) is the same file.
        with open(B.__file__, encoding="utf-8") as f:
            self.assertEqual(f.read(), committed, f"{B.__file__} differs from the source tree: reinstall")

    def test_every_prototype_parsed(self):
        # Independent count: every "skb_xxx(" that starts a declaration in the header.
        import re
        declared = set(re.findall(r"^\S.*?\b(skb_\w+)\(", self.header, flags=re.M))
        declared -= {n for n in declared if n.startswith("skb_progress_fn")}
        self.assertEqual(declared, set(B.FUNCTIONS))
        self.assertGreaterEqual(len(B.FUNCTIONS), 130)

    def test_library_exports_match_declarations(self):
        nm = shutil.which("nm")
        if nm is None:
            self.skipTest("SKIPPED: nm not installed")
        out = subprocess.run([nm, "-D", "--defined-only", sketchbody.library_path()], check=True,
                             capture_output=True, text=True).stdout
        exported = {line.split()[-1] for line in out.splitlines() if line.split()[-1].startswith("skb_")}
        hint = ("regenerate the header (scripts/gen-header.sh) and the bindings (python3 python/tools/gen_bindings.py), "
                f"and rebuild the library ({sketchbody.library_path()})")
        self.assertEqual(exported - set(B.FUNCTIONS), set(), f"exported but not declared: {hint}")
        self.assertEqual(set(B.FUNCTIONS) - exported, set(), f"declared but not exported: {hint}")

    def test_pointer_depth_of_every_argument(self):
        def depth_ct(t):
            if t in (ctypes.c_char_p, ctypes.c_void_p):
                return 1
            if isinstance(t, type) and issubclass(t, ctypes._Pointer):
                return 1 + depth_ct(t._type_)
            return 0

        for name, (restype, argtypes, cret, params) in B.FUNCTIONS.items():
            self.assertEqual(len(argtypes), len(params), name)
            for t, (pname, ctype) in zip(argtypes, params):
                want = ctype.count("*")
                if ctype == "skb_progress_fn":
                    self.assertIs(t, B.skb_progress_fn)
                    continue
                self.assertEqual(depth_ct(t), want, f"{name}({pname}: {ctype})")
            if cret == "skb_status":
                self.assertIs(restype, ctypes.c_uint32, name)
            elif cret == "void":
                self.assertIsNone(restype, name)
            else:
                self.assertEqual(cret, "const char *", name)
                self.assertIs(restype, ctypes.c_char_p, name)

    def test_layouts_constants_and_prototypes_against_a_c_compiler(self):
        cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
        if cc is None:
            self.skipTest("SKIPPED: no C compiler")
        src = ["#include <stdio.h>", "#include <stddef.h>", '#include "sketchbody.h"', "int main(void) {"]
        for name, v in B.CONSTANTS.items():
            if isinstance(v, float):
                src.append(f'  printf("const {name} %.17g\\n", (double){name});')
            else:
                src.append(f'  printf("const {name} %lld\\n", (long long){name});')
        for value, name in B.STATUS_NAMES.items():
            src.append(f'  printf("const {name} %lld\\n", (long long){name});')
        for sname, fields in B.STRUCT_FIELDS.items():
            src.append(f'  printf("size {sname} %zu\\n", sizeof(struct {sname}));')
            for fname, _ in fields:
                src.append(f'  printf("offset {sname}.{fname} %zu\\n", offsetof(struct {sname}, {fname}));')
        for ctype in self.gen.SCALARS:
            src.append(f'  printf("scalar {ctype} %zu %d\\n", sizeof({ctype}), (int)(({ctype})-1 < ({ctype})0));')
        for name, (_, _, cret, params) in B.FUNCTIONS.items():
            args = ", ".join(ct for _, ct in params) or "void"
            src.append(f"  _Static_assert(__builtin_types_compatible_p(__typeof__(&{name}), {cret} (*)({args})), "
                       f'"prototype of {name}");')
        src += ["  return 0;", "}"]
        with tempfile.TemporaryDirectory() as tmp:
            c, exe = os.path.join(tmp, "check.c"), os.path.join(tmp, "check")
            with open(c, "w") as f:
                f.write("\n".join(src) + "\n")
            r = subprocess.run([cc, "-std=gnu11", "-Wall", "-Werror", "-I", os.path.join(ROOT, "include"), c, "-o", exe],
                               capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr[-4000:])
            out = subprocess.run([exe], check=True, capture_output=True, text=True).stdout
        seen = {"const": 0, "size": 0, "offset": 0, "scalar": 0}
        for line in out.splitlines():
            kind, key, *vals = line.split()
            seen[kind] += 1
            if kind == "const":
                want = getattr(B, key)
                self.assertEqual(want, type(want)(vals[0]) if isinstance(want, float) else int(vals[0]), key)
            elif kind == "size":
                self.assertEqual(ctypes.sizeof(getattr(B, key)), int(vals[0]), key)
            elif kind == "offset":
                sname, fname = key.split(".")
                self.assertEqual(getattr(getattr(B, sname), fname).offset, int(vals[0]), key)
            elif kind == "scalar":
                t = eval(self.gen.SCALARS[key], {"ctypes": ctypes})  # noqa: S307 - our own table
                self.assertEqual(ctypes.sizeof(t), int(vals[0]), key)
                if t not in (ctypes.c_bool, ctypes.c_char, ctypes.c_float, ctypes.c_double):
                    self.assertEqual(t(-1).value < 0, bool(int(vals[1])), f"signedness of {key}")
        self.assertEqual(seen["const"], len(B.CONSTANTS) + len(B.STATUS_NAMES))
        self.assertEqual(seen["size"], len(B.STRUCT_FIELDS))
        print(f"\n  C check: {seen['const']} constants/statuses, {seen['size']} structs, {seen['offset']} fields, "
              f"{len(B.FUNCTIONS)} prototypes, {seen['scalar']} scalar types", end=" ")

    def test_documented_struct_sizes(self):
        self.assertEqual(ctypes.sizeof(B.skb_image), 24)
        self.assertEqual(ctypes.sizeof(B.skb_camera), 104)
        self.assertEqual(ctypes.sizeof(B.skb_joints2d), 256)
        self.assertEqual(ctypes.sizeof(B.skb_pose3d), 880)

    def test_check_mode_of_the_generator(self):
        r = subprocess.run([sys.executable, TOOLS, "--check"], capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)


if __name__ == "__main__":
    unittest.main(verbosity=2)
