"""The packages' layering (doc/architecture.md): the engine ``lbmd`` never
imports the cell model ``oif``, and ``oif`` uses lbmd's public API only.

Read from the sources (Python's ast), so that an import inside a function
counts as much as one at the top:

- no module of lbmd imports oif or looks it up in sys.modules;
- no module of oif imports lbmd._lbmd (the compiled module) or any other
  private lbmd module or name, and none reads an attribute whose name is
  private to lbmd (a name starting with one underscore that lbmd defines
  and oif does not: system._core, bonded_inter._id_of, ...);
- at run time, importing lbmd, making a System with a fluid and checking
  its settings loads no oif module.

Each check is also run on a snippet that breaks it: the checks can fail.
"""
import ast
import glob
import os
import re
import subprocess
import unittest

SOURCE = os.environ.get("PYOIF_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
LBMD = os.path.join(SOURCE, "src", "python", "lbmd")
OIF = os.path.join(SOURCE, "src", "pyoif", "oif")
PRIVATE = re.compile(r"_[A-Za-z]\w*")


def parse(path):
    with open(path, encoding="utf-8") as f:
        return ast.parse(f.read(), filename=path)


def imported_modules(tree):
    """(line, module) of every import, the names of `from m import a` as m.a."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            out += [(node.lineno, node.module)] + [(node.lineno, f"{node.module}.{a.name}") for a in node.names]
    return out


def imports_of_oif(tree):
    """Where an lbmd module imports oif or reads it from sys.modules."""
    found = [f"line {line}: import {m}" for line, m in imported_modules(tree) if m == "oif" or m.startswith("oif.")]
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and re.fullmatch(r"oif(\.\w+)*", node.value):
            found.append(f"line {node.lineno}: the module name {node.value!r}")
    return found


def defined_names(trees):
    """Every name the sources define: functions, classes, assigned names and
    attributes, and strings that look like names (self.__dict__["_x"])."""
    out = set()
    for tree in trees:
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                out.add(node.name)
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
                out.add(node.attr)
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
                out.add(node.id)
            elif isinstance(node, ast.Constant) and isinstance(node.value, str) and PRIVATE.fullmatch(node.value):
                out.add(node.value)
    return out


def private_uses(tree, lbmd_private, own_names):
    """Where an oif module imports a private lbmd module or name, or reads an
    attribute private to lbmd."""
    found = []
    for line, m in imported_modules(tree):
        parts = m.split(".")
        if parts[0] == "lbmd" and any(PRIVATE.fullmatch(p) for p in parts[1:]):
            found.append(f"line {line}: import {m}")
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr in lbmd_private and node.attr not in own_names:
            found.append(f"line {node.lineno}: .{node.attr}")
    return found


class Layering(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.lbmd_files = sorted(glob.glob(os.path.join(LBMD, "*.py")))
        cls.oif_files = sorted(glob.glob(os.path.join(OIF, "*.py")))
        assert cls.lbmd_files and cls.oif_files, (LBMD, OIF)
        cls.lbmd_trees = {p: parse(p) for p in cls.lbmd_files}
        cls.oif_trees = {p: parse(p) for p in cls.oif_files}
        cls.lbmd_private = {n for n in defined_names(cls.lbmd_trees.values())
                            if PRIVATE.fullmatch(n) and not n.startswith("__")}
        cls.oif_names = defined_names(cls.oif_trees.values())

    def test_the_checks_can_fail(self):
        self.assertEqual(len(imports_of_oif(ast.parse("def f():\n    import oif.geometry\n"))), 1)
        self.assertEqual(len(imports_of_oif(ast.parse("import sys\nm = sys.modules.get('oif.oif_classes')\n"))), 1)
        self.assertEqual(imports_of_oif(ast.parse("import lbmd\nx = 'oif is a package'\n")), [])
        self.assertIn("_core", self.lbmd_private)
        bad = ast.parse("from lbmd import _lbmd\nimport lbmd._lbmd\ndef f(s):\n    return s._core\n")
        self.assertEqual(len(private_uses(bad, self.lbmd_private, set())), 3)
        self.assertEqual(private_uses(ast.parse("def f(s):\n    return s.part\n"), self.lbmd_private, set()), [])

    def test_lbmd_never_imports_oif(self):
        found = {os.path.basename(p): imports_of_oif(t) for p, t in self.lbmd_trees.items()}
        self.assertEqual({k: v for k, v in found.items() if v}, {},
                         "lbmd must not import oif: cells reach the engine through lbmd.cell_registry")

    def test_oif_uses_public_lbmd_only(self):
        found = {os.path.basename(p): private_uses(t, self.lbmd_private, self.oif_names)
                 for p, t in self.oif_trees.items()}
        self.assertEqual({k: v for k, v in found.items() if v}, {},
                         "oif must use lbmd's public API only (give lbmd a public call instead)")

    def test_lbmd_alone_loads_no_oif(self):
        script = ("import sys, lbmd\n"
                  "from lbmd import lb\n"
                  "s = lbmd.System(box_l=[8, 8, 8])\n"
                  "s.time_step = 0.1\n"
                  "s.actors.add(lb.LBFluid(agrid=1, dens=1, visc=1, tau=0.1))\n"
                  "s.check_settings()\n"
                  "s.integrator.run(2)\n"
                  "print(sorted(m for m in sys.modules if m == 'oif' or m.startswith('oif.')))\n")
        launcher = os.path.join(os.environ.get("PYOIF_BUILD_DIR", ""), "pyoif")
        out = subprocess.run([launcher, "-c", script], capture_output=True, text=True, timeout=300)
        self.assertEqual(out.returncode, 0, out.stderr[-3000:])
        self.assertEqual(out.stdout.strip().splitlines()[-1], "[]")


if __name__ == "__main__":
    unittest.main()
