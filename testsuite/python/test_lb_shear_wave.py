"""Decay of a transverse shear wave u_z(x) = A sin(k x) in a periodic box:
the amplitude decays as exp(-nu k^2 t). The viscosity fitted from the decay
(updates 30..400, after the start-up transient of the equilibrium
initialisation) must be within 1 % of visc, for MRT, TRT and BGK.

Galilean invariance: the same wave on top of a uniform flow u0 along x (the
wave vector; the wave is advected, its Fourier amplitude decays) must give
the same viscosity within 1 % (u0 = 0.03 in lattice units; the second-order
equilibrium's O(u0^2) error is ~0.3 %) and a mean flow that stays u0
(relative 1e-10)."""
import unittest

import numpy as np

import lbmd
import lbmd.lb

N = 40


def measured_viscosity(collision, u0=0.0, nu_lattice=0.12):
    agrid, tau = 0.25, 0.01
    visc = nu_lattice * agrid ** 2 / tau
    system = lbmd.System(box_l=[N * agrid, 2 * agrid, 2 * agrid])
    system.time_step = tau
    lbf = lbmd.lb.LBFluid(agrid=agrid, dens=0.8, visc=visc, tau=tau, collision=collision,
                          bulk_visc=2 * visc)
    system.actors.add(lbf)
    x = (np.arange(N) + 0.5) * agrid
    k = 2 * np.pi / (N * agrid)
    amp = 0.01 * agrid / tau
    u = np.zeros((N, 2, 2, 3))
    u[..., 0] = u0 * agrid / tau
    u[..., 2] = amp * np.sin(k * x)[:, None, None]
    lbf[:, :, :].velocity = u
    times, amps = [], []
    phase = np.exp(-1j * k * x)
    for step in range(401):
        if step >= 30 and step % 10 == 0:
            uz = lbf[:, 0, 0].velocity[:, 2]
            times.append(step * tau)
            amps.append(abs(np.sum(uz * phase)) * 2 / N)
        system.integrator.run(1)
    mean_ux = np.mean(lbf[:, :, :].velocity[..., 0])
    slope = np.polyfit(times, np.log(amps), 1)[0]
    return -slope / k ** 2 / visc, mean_ux / (agrid / tau)


class ShearWave(unittest.TestCase):

    def test_viscosity(self):
        for collision in ("MRT", "TRT", "BGK"):
            ratio, _ = measured_viscosity(collision)
            self.assertAlmostEqual(ratio, 1.0, delta=0.01, msg=collision)

    def test_galilean_invariance(self):
        for collision in ("MRT", "TRT"):
            at_rest, _ = measured_viscosity(collision)
            moving, mean_u = measured_viscosity(collision, u0=0.03)
            self.assertAlmostEqual(moving, 1.0, delta=0.01, msg=collision)
            self.assertAlmostEqual(moving / at_rest, 1.0, delta=0.01, msg=collision)
            self.assertAlmostEqual(mean_u, 0.03, delta=0.03 * 1e-10)


if __name__ == "__main__":
    unittest.main()
