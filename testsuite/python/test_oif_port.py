"""The porting rule: a PyOIF (ESPResSo 4.2 + object_in_fluid) script runs
after replacing 'espressomd' by 'lbmd' and 'object_in_fluid' by 'oif' in
its text. Two scripts written the way PyOIF users write them: the elastic
relaxation of a stretched sphere (the check of ESPResSo's
oif_volume_conservation test, with its expected decay rate), and a channel
with fluid, walls, obstacles, contacts and VTK output."""
import os
import subprocess
import sys
import tempfile
import textwrap
import unittest


from testsuite_data import TEST_MESHES

RELAXATION_SCRIPT = textwrap.dedent("""
    import sys
    import numpy as np
    import scipy.optimize
    import espressomd
    import object_in_fluid as oif

    data = sys.argv[1]
    system = espressomd.System(box_l=(50., 50., 50.))
    system.time_step = 0.4
    system.cell_system.skin = 0.5

    for stretching in ({"kslin": 1.}, {"ks": 1.}):
        cell_type = oif.OifCellType(nodes_file=data + "/sphere393nodes.dat",
                                    triangles_file=data + "/sphere393triangles.dat",
                                    system=system, **stretching, kb=1.0, kal=1.0, kag=0.1, kv=0.1,
                                    check_orientation=False, resize=(3.0, 3.0, 3.0))
        half = np.copy(system.box_l) / 2.
        cell = oif.OifCell(cell_type=cell_type, particle_type=0, origin=half)
        parts = system.part.all()
        d0 = cell.diameter()
        assert abs(d0 - 24.) < 1e-3, d0
        parts.pos = (parts.pos - half) * 1.5 + half
        parts.pos = parts.pos * np.array((0.96, 1.05, 1.02))
        system.integrator.run(1)
        assert np.allclose(np.sum(parts.f, axis=0), 0., atol=1e-10)
        torque = np.zeros(3)
        for p in system.part.all():
            torque += np.cross(p.pos, p.f)
        assert np.allclose(torque, 0., atol=1e-10), torque
        system.thermostat.set_langevin(kT=0, gamma=0.7, seed=42)
        system.integrator.run(steps=50)
        xdata, ydata = [], []
        for _ in range(20):
            system.integrator.run(steps=20)
            xdata.append(system.time)
            ydata.append(cell.diameter())
        (pref, lam, _, d_final), _ = scipy.optimize.curve_fit(
            lambda x, a, b, c, d: a * np.exp(-b * x + c) + d, xdata, ydata,
            p0=[3., 0.03, 0., d0], bounds=([-np.inf, 0., -np.inf, 0.], 4 * [np.inf]))
        print("stretching", stretching, "decay rate", lam, "final diameter", d_final)
        assert pref > 0
        assert abs(d_final - d0) < 0.005, d_final
        assert abs(lam - 325e-4) < 5e-4, lam
        system.thermostat.turn_off()
        system.part.clear()
    assert system.max_oif_objects == 2
    print("OK")
""")

CHANNEL_SCRIPT = textwrap.dedent("""
    import os
    import sys
    import espressomd
    from espressomd import lb
    from espressomd import lbboundaries
    from espressomd import shapes
    import object_in_fluid as oif
    from object_in_fluid.oif_utils import output_vtk_rhomboid, output_vtk_cylinder

    required_features = ["LB_BOUNDARIES", "EXTERNAL_FORCES", "SOFT_SPHERE", "MEMBRANE_COLLISION",
                         "OIF_GLOBAL_FORCES", "OIF_LOCAL_FORCES", "MASS"]
    espressomd.assert_features(required_features)

    data, out = sys.argv[1], sys.argv[2]
    boxX, boxY, boxZ = 22.0, 14.0, 15.0
    system = espressomd.System(box_l=(boxX, boxY, boxZ))
    system.time_step = 0.1
    system.cell_system.skin = 0.2

    cell_type = oif.OifCellType(nodes_file=data + "/rbc374nodes.dat", triangles_file=data + "/rbc374triangles.dat",
                                system=system, ks=0.02, kb=0.016, kal=0.02, kag=0.9, kv=1.0,
                                check_orientation=False, resize=(2.0, 2.0, 2.0), normal=True)
    cell0 = oif.OifCell(cell_type=cell_type, particle_type=0, origin=[5.0, 5.0, 3.5])
    cell1 = oif.OifCell(cell_type=cell_type, particle_type=1, origin=[5.0, 5.0, 8.0])

    lbf = espressomd.lb.LBFluid(agrid=1, dens=1.0, visc=1.5, tau=0.1, ext_force_density=[0.002, 0.0, 0.0])
    system.actors.add(lbf)
    system.thermostat.set_lb(LB_fluid=lbf, gamma=1.5)

    boundaries = []
    bottom = shapes.Rhomboid(corner=[0.0, 0.0, 0.0], a=[boxX, 0.0, 0.0], b=[0.0, boxY, 0.0],
                             c=[0.0, 0.0, 1.0], direction=1)
    boundaries.append(bottom)
    output_vtk_rhomboid(bottom, out_file=out + "/wallBottom.vtk")
    top = shapes.Rhomboid(corner=[0.0, 0.0, boxZ - 1], a=[boxX, 0.0, 0.0], b=[0.0, boxY, 0.0],
                          c=[0.0, 0.0, 1.0], direction=1)
    boundaries.append(top)
    output_vtk_rhomboid(top, out_file=out + "/wallTop.vtk")
    cyl = shapes.Cylinder(center=[14.0, 7.0, 7.5], axis=[0.0, 0.0, 1.0], length=13.0, radius=2.0, direction=1)
    boundaries.append(cyl)
    output_vtk_cylinder(cyl, n=20, out_file=out + "/cylinder.vtk")
    for boundary in boundaries:
        system.lbboundaries.add(lbboundaries.LBBoundary(shape=boundary))
        system.constraints.add(shape=boundary, particle_type=10)

    system.non_bonded_inter[0, 10].soft_sphere.set_params(a=0.0001, n=1.2, cutoff=0.1, offset=0.0)
    system.non_bonded_inter[1, 10].soft_sphere.set_params(a=0.0001, n=1.2, cutoff=0.1, offset=0.0)
    system.non_bonded_inter[0, 1].membrane_collision.set_params(a=0.0001, n=1.2, cutoff=0.1, offset=0.0)

    cell0.output_vtk_pos_folded(file_name=out + "/cell0_0.vtk")
    cell1.output_vtk_pos_folded(file_name=out + "/cell1_0.vtk")
    x0 = cell0.get_origin()[0]
    for i in range(1, 4):
        system.integrator.run(steps=100)
        cell0.output_vtk_pos_folded(file_name=out + "/cell0_" + str(i) + ".vtk")
        cell1.output_vtk_pos_folded(file_name=out + "/cell1_" + str(i) + ".vtk")
        print("time: ", str(i * 100 * system.time_step), "volume", cell0.volume())
    assert cell0.get_origin()[0] > x0, "the fluid carries the cell along +x"
    assert abs(cell0.volume() / cell_type.mesh.volume() - 1) < 0.01
    print("Simulation completed.")
""")


def port(text):
    return text.replace("espressomd", "lbmd").replace("object_in_fluid", "oif")


class TestPort(unittest.TestCase):

    def run_script(self, text, *args):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "script.py")
            with open(path, "w") as f:
                f.write(port(text))
            out = os.path.join(tmp, "out")
            os.mkdir(out)
            res = subprocess.run([sys.executable, path, TEST_MESHES, out, *args],
                                 capture_output=True, text=True, timeout=600)
            files = sorted(os.listdir(out))
        self.assertEqual(res.returncode, 0, res.stdout + res.stderr)
        return res.stdout, files

    def test_port_rule(self):
        self.assertIn("import lbmd", port("import espressomd"))
        self.assertIn("import oif as oif", port("import object_in_fluid as oif"))
        self.assertIn("from oif.oif_utils import output_vtk_rhomboid",
                      port("from object_in_fluid.oif_utils import output_vtk_rhomboid"))

    def test_relaxation_script(self):
        stdout, _ = self.run_script(RELAXATION_SCRIPT)
        self.assertIn("OK", stdout)

    def test_channel_script(self):
        stdout, files = self.run_script(CHANNEL_SCRIPT)
        self.assertIn("Simulation completed.", stdout)
        self.assertIn("cell1_3.vtk", files)
        self.assertIn("cylinder.vtk", files)


if __name__ == "__main__":
    unittest.main()
