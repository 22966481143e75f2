"""LiveView stops on a SIGINT sent in the middle of a run, between two steps,
with the state of a plain run of the steps it did. One rank only (Ctrl-C
reaches one process), so it is not among the tests the CMakeLists also runs
on 2 ranks; the rest of LiveView is in test_visualization.py."""
import os
import subprocess
import unittest

from lbmd import visualization as vis

import test_visualization as shared  # a module: its TestCases do not run again here


class Interrupt(unittest.TestCase):
    assert_same_state = shared.Live.assert_same_state

    def test_interrupt_during_a_run(self):
        """SIGINT in the middle of a chunk: the engine stops between steps."""
        system, fluid, cells = shared.scene()
        # from another process: the run keeps the GIL, a Python thread could not send it
        view = vis.LiveView(system, every=200000, display="none")
        view.draw()
        killer = subprocess.Popen(["sh", "-c", f"sleep 1; kill -INT {os.getpid()}"])
        done = view.run(400000)
        killer.wait()
        self.assertTrue(view.interrupted)
        self.assertGreater(done, 0)
        self.assertLess(done, 200000)  # within the first chunk
        reference, ref_fluid, _ = shared.scene()
        reference.integrator.run(done)
        self.assert_same_state(shared.state(system, fluid), shared.state(reference, ref_fluid))


if __name__ == "__main__":
    unittest.main()
