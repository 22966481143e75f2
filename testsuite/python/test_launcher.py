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
        for mode in ("--ipython", "notebook", "lab", "--install-kernel"):
            self.assertIn(mode, out.stdout)
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

    def test_ipython(self):
        out = self.run_pyoif(os.path.join(BUILD, "pyoif"), "--ipython", "--no-banner", "--colors=NoColor",
                             stdin="import lbmd, oif; print('FROM', lbmd.__file__, oif.__name__)\n")
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertIn("FROM " + os.path.join(BUILD, "python", "lbmd"), out.stdout)
        out = self.run_pyoif(os.path.join(BUILD, "pyoif"), "--ipython", "-c", "import IPython, lbmd; "
                             "print('IPY', IPython.get_ipython() is not None, lbmd.size)")
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertIn("IPY True 1", out.stdout)

    def test_notebook_starts(self):
        """`pyoif notebook` runs Debian's Jupyter notebook (here only its
        version: a server would wait for a browser)."""
        out = self.run_pyoif(os.path.join(BUILD, "pyoif"), "notebook", "--version")
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertRegex(out.stdout.strip(), r"^\d+\.\d+")

    def test_lab_or_notebook_message(self):
        """`pyoif lab` without Jupyter Lab says so (Debian 12 has none)."""
        probe = subprocess.run(["/usr/bin/python3", "-c", "import jupyterlab"], capture_output=True)
        if probe.returncode == 0:
            self.skipTest("Jupyter Lab is installed")
        out = self.run_pyoif(os.path.join(BUILD, "pyoif"), "lab", "--version")
        self.assertNotEqual(out.returncode, 0)
        self.assertIn("Jupyter Lab is not installed", out.stderr)
        self.assertIn("pyoif notebook", out.stderr)

    def kernelspecs(self, jupyter_path):
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "JUPYTER_PATH")}
        env["JUPYTER_PATH"] = jupyter_path
        out = subprocess.run(["/usr/bin/python3", "-m", "jupyter_client.kernelspecapp", "list"],
                             capture_output=True, text=True, env=env, timeout=120)
        self.assertEqual(out.returncode, 0, out.stderr)
        return out.stdout

    def execute_notebook(self, jupyter_path):
        """A tiny notebook on the kernel "pyoif" (nbclient), as Jupyter
        would run it with that JUPYTER_PATH; returns its first output."""
        import nbformat
        from nbclient import NotebookClient
        nb = nbformat.v4.new_notebook()
        nb.cells.append(nbformat.v4.new_code_cell("import lbmd, oif\nprint('KERNEL', lbmd.__file__, "
                                                  "oif.__name__)"))
        from unittest import mock
        with mock.patch.dict(os.environ, {"JUPYTER_PATH": jupyter_path}):  # restored afterwards
            os.environ.pop("PYTHONPATH", None)  # the kernel spec must bring it
            NotebookClient(nb, kernel_name="pyoif", timeout=120).execute()
        return nb.cells[0].outputs[0]["text"]

    def test_kernel_spec_build_tree(self):
        jupyter = os.path.join(BUILD, "share", "jupyter")
        self.assertIn(os.path.join(jupyter, "kernels", "pyoif"), self.kernelspecs(jupyter))
        self.assertIn("KERNEL " + os.path.join(BUILD, "python", "lbmd"), self.execute_notebook(jupyter))
        with tempfile.TemporaryDirectory() as prefix:  # --install-kernel --prefix: jupyter kernelspec install
            out = self.run_pyoif(os.path.join(BUILD, "pyoif"), "--install-kernel", "--prefix", prefix)
            self.assertEqual(out.returncode, 0, out.stderr)
            spec = os.path.join(prefix, "share", "jupyter", "kernels", "pyoif", "kernel.json")
            with open(spec) as f:
                self.assertIn(os.path.join(BUILD, "python"), f.read())

    def test_installed_kernel_spec(self):
        with tempfile.TemporaryDirectory() as prefix:
            inst = subprocess.run(["cmake", "--install", BUILD, "--prefix", prefix],
                                  capture_output=True, text=True, timeout=300)
            self.assertEqual(inst.returncode, 0, inst.stderr)
            jupyter = os.path.join(prefix, "share", "jupyter")
            listed = self.kernelspecs(jupyter)
            self.assertIn("pyoif", listed)
            self.assertIn(os.path.join(jupyter, "kernels", "pyoif"), listed)
            self.assertIn("KERNEL " + os.path.join(prefix, "lib", "pyoif", "python", "lbmd"),
                          self.execute_notebook(jupyter))


if __name__ == "__main__":
    unittest.main()
