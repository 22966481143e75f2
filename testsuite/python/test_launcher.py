"""The pyoif launcher: scripts with arguments, interactive mode, --help,
and the installed launcher from `cmake --install`."""
import os
import subprocess
import tempfile
import unittest

BUILD = os.environ.get("PYOIF_BUILD_DIR")


@unittest.skipUnless(BUILD, "PYOIF_BUILD_DIR not set (run through CTest)")
class Launcher(unittest.TestCase):
    def run_pyoif(self, launcher, *args, stdin=None):
        env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
        return subprocess.run([launcher, *args], input=stdin, capture_output=True, text=True,
                              env=env, timeout=120)

    def test_script_with_arguments(self):
        with tempfile.NamedTemporaryFile("w", suffix=".py", delete=False) as f:
            f.write("import sys, lbmd, oif\nprint('ARGS', sys.argv[1:], sys.executable)\n")
        out = self.run_pyoif(os.path.join(BUILD, "pyoif"), f.name, "--small", "3")
        os.unlink(f.name)
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertIn("ARGS ['--small', '3'] /usr/bin/python3", out.stdout)

    def test_interactive(self):
        out = self.run_pyoif(os.path.join(BUILD, "pyoif"),
                             stdin="s = lbmd.System(box_l=[1, 2, 3])\nprint('BOX', s.box_l[1])\n")
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertIn("BOX 2.0", out.stdout)

    def test_help(self):
        out = self.run_pyoif(os.path.join(BUILD, "pyoif"), "--help")
        self.assertEqual(out.returncode, 0)
        self.assertIn("--gdb", out.stdout)
        self.assertIn("--valgrind", out.stdout)

    def test_error_exit_code(self):
        out = self.run_pyoif(os.path.join(BUILD, "pyoif"), "-c",
                             "import lbmd; lbmd.System(box_l=[1, 1])")
        self.assertNotEqual(out.returncode, 0)
        self.assertIn("ValueError", out.stderr)
        self.assertIn("box_l", out.stderr)

    def test_installed_launcher(self):
        with tempfile.TemporaryDirectory() as prefix:
            inst = subprocess.run(["cmake", "--install", BUILD, "--prefix", prefix],
                                  capture_output=True, text=True, timeout=300)
            self.assertEqual(inst.returncode, 0, inst.stderr)
            out = self.run_pyoif(os.path.join(prefix, "bin", "pyoif"), "-c",
                                 "import lbmd, oif; print('FROM', lbmd.__file__)")
            self.assertEqual(out.returncode, 0, out.stderr)
            self.assertIn("FROM " + prefix, out.stdout)


if __name__ == "__main__":
    unittest.main()
