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
        self.assertIn("--all-ranks", out.stdout)
        self.assertIn("only rank\n0's stdout is shown", out.stdout)  # the help's last line is printed

    def test_rank_from_each_mpi_launcher(self):
        """The rank comes from Open MPI's, MPICH's or PMIx's environment: a
        rank other than 0 prints nothing on stdout (but on stderr), unless
        --all-ranks or PYOIF_ALL_RANKS=1. (No MPI here: the script does not
        import lbmd, so the variables only reach the launcher.)"""
        launcher = os.path.join(BUILD, "pyoif")
        code = "import sys; print('OUT'); print('ERR', file=sys.stderr)"
        for var in ("OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"):
            for rank, all_ranks, args, shown in (("1", None, [], False), ("0", None, [], True),
                                                 ("1", None, ["--all-ranks"], True), ("1", "1", [], True),
                                                 ("1", "0", [], False)):
                env = {k: v for k, v in os.environ.items()
                       if k not in ("PYTHONPATH", "PYOIF_ALL_RANKS", "OMPI_COMM_WORLD_RANK", "PMI_RANK",
                                    "PMIX_RANK")}
                env[var] = rank
                if all_ranks is not None:
                    env["PYOIF_ALL_RANKS"] = all_ranks
                out = subprocess.run([launcher, *args, "-c", code], capture_output=True, text=True,
                                     env=env, timeout=120)
                with self.subTest(var=var, rank=rank, all_ranks=all_ranks, args=args):
                    self.assertEqual(out.returncode, 0, out.stderr)
                    self.assertEqual(out.stdout, "OUT\n" if shown else "")
                    self.assertIn("ERR", out.stderr)

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
