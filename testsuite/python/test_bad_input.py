"""The bad-input catalogue (doc/bad-input.md): one entry per user mistake,
each giving a Python exception (or, where the run can go on, a warning) of
the listed type whose message holds the listed words, and after each the
system is still usable: nothing half-applied (particles, box, time step,
actors, constraints as before), a few steps run, positions stay finite, the
fluid's mass is unchanged.

``python3 test_bad_input.py --markdown`` prints the catalogue's table (the
one in doc/bad-input.md)."""
import math
import os
import sys
import tempfile
import unittest
import warnings

import numpy as np

import lbmd
from lbmd.settings_check import SettingsWarning
import oif

INF, NAN = math.inf, math.nan
SPHERE = oif.mesh_files("sphere162")


class Case:
    def __init__(self, key, what, exc, gist, scene, fn):
        self.key, self.what, self.exc, self.gist, self.scene, self.fn = key, what, exc, gist, scene, fn


CASES = []


def case(what, exc, *gist, scene="plain"):
    """Register a mistake: `what` the user did, `exc` the exception (or
    warning) class, `gist` words the message must contain (case-insensitive)."""
    def deco(fn):
        CASES.append(Case(fn.__name__, what, exc, gist, scene, fn))
        return fn
    return deco


class Scene:
    """A small system: 'plain' (two particles, periodic box), 'fluid' (a
    fluid coupled to one particle), 'cell' (one OIF cell, Langevin),
    'fluid_cell' (a cell in a fluid)."""

    def __init__(self, kind, tmp):
        self.kind, self.tmp = kind, tmp
        self.lbf = self.cell = self.cell_type = None
        box = 16.0 if "cell" in kind else 8.0
        s = self.system = lbmd.System(box_l=[box] * 3)
        s.time_step = 0.1
        s.cell_system.skin = 0.2
        if "fluid" in kind:
            self.lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=0.5, tau=0.1)
            s.actors.add(self.lbf)
        if "cell" in kind:
            self.cell_type = oif.OifCellType(*SPHERE, system=s, resize=(2.0,) * 3, ks=0.01, kb=0.01,
                                             kal=0.01, kag=0.1, kv=0.1, normal=True)
            self.cell = oif.OifCell(cell_type=self.cell_type, particle_type=0, origin=[box / 2] * 3)
        else:
            s.part.add(pos=[[1.0, 2.0, 3.0], [4.0, 4.5, 5.0]], v=[[0.01, 0, 0], [0, 0.01, 0]])
        if self.lbf is not None:
            s.thermostat.set_lb(LB_fluid=self.lbf, gamma=1.0)
        else:
            s.thermostat.set_langevin(kT=0.0, gamma=0.5)

    def snapshot(self):
        s = self.system
        return dict(n=len(s.part), pos=s.part.all().pos.copy(), box=s.box_l.copy(), dt=s.time_step,
                    actors=len(s.actors), constraints=len(s.constraints), periodicity=list(s.periodicity),
                    mass=self.lbf.total_mass() if self.lbf is not None else None)

    def path(self, name):
        return os.path.join(self.tmp, name)


def mesh_files_from(sc, nodes, triangles):
    """Write nodes/triangles (text, or arrays) into sc's folder; their paths."""
    out = []
    for name, data in (("nodes.dat", nodes), ("triangles.dat", triangles)):
        path = sc.path(name)
        with open(path, "w") as f:
            if isinstance(data, str):
                f.write(data)
            else:
                np.savetxt(f, data, fmt="%d" if np.asarray(data).dtype.kind == "i" else "%.17g")
        out.append(path)
    return out


def sphere_arrays():
    return np.loadtxt(SPHERE[0]), np.loadtxt(SPHERE[1], dtype=np.int64)


def cell_type_from(sc, nodes, triangles, **kw):
    return oif.OifCellType(*mesh_files_from(sc, nodes, triangles), system=sc.system, **kw)


# --- System --------------------------------------------------------------------
@case("System(box_l='10 10 10'): a string for the box", TypeError, "box_l", "3 numbers")
def system_box_string(sc):
    lbmd.System(box_l="10 10 10")


@case("System(box_l=[10, 10]): two lengths for three", ValueError, "box_l", "3 numbers")
def system_box_2vec(sc):
    lbmd.System(box_l=[10, 10])


@case("System(box_l=[10, -10, 10]): a negative length", ValueError, "box_l", "positive")
def system_box_negative(sc):
    lbmd.System(box_l=[10, -10, 10])


@case("System(box_l=[10, 0, 10]): a zero length", ValueError, "box_l", "positive")
def system_box_zero(sc):
    lbmd.System(box_l=[10, 0, 10])


@case("System(box_l=[10, nan, 10])", ValueError, "box_l", "finite")
def system_box_nan(sc):
    lbmd.System(box_l=[10, NAN, 10])


@case("System(box_l=[inf, 10, 10])", ValueError, "box_l", "finite")
def system_box_inf(sc):
    lbmd.System(box_l=[INF, 10, 10])


@case("System(box_l=[[1, 2, 3], [4, 5]]): a ragged list", TypeError, "box_l", "3 numbers")
def system_box_ragged(sc):
    lbmd.System(box_l=[[1, 2, 3], [4, 5]])


@case("System(box=...): a misspelt keyword", TypeError, "unknown parameter", "box")
def system_unknown_keyword(sc):
    lbmd.System(box=[10, 10, 10])


@case("System(periodicity=[True, False]): two flags for three", ValueError, "periodicity", "3 booleans")
def system_periodicity_2(sc):
    lbmd.System(box_l=[10, 10, 10], periodicity=[True, False])


@case("system.time_step = 0", ValueError, "time_step", "> 0")
def system_dt_zero(sc):
    sc.system.time_step = 0


@case("system.time_step = -0.1", ValueError, "time_step", "> 0")
def system_dt_negative(sc):
    sc.system.time_step = -0.1


@case("system.time_step = '0.1': a string for a number", TypeError, "time_step", "number")
def system_dt_string(sc):
    sc.system.time_step = "0.1"


@case("system.time_step = nan", ValueError, "time_step", "finite")
def system_dt_nan(sc):
    sc.system.time_step = NAN


@case("system.timestep = 0.1: a misspelt attribute (would set nothing)", AttributeError, "timestep")
def system_misspelt_attribute(sc):
    sc.system.timestep = 0.1


@case("system.box_l = [8, 8]: two lengths", ValueError, "box_l", "3 numbers")
def system_box_set_2vec(sc):
    sc.system.box_l = [8, 8]


@case("system.cell_system.skin = -1", ValueError, "skin")
def system_skin_negative(sc):
    sc.system.cell_system.skin = -1


@case("integrator.run() on a System without a time step", RuntimeError, "time_step")
def system_run_no_dt(sc):
    s = lbmd.System(box_l=[5, 5, 5])
    s.part.add(pos=[1, 1, 1])
    s.integrator.run(1)


@case("integrator.run(-5)", ValueError, "steps")
def system_run_negative(sc):
    sc.system.integrator.run(-5)


@case("integrator.run(2.5): a fraction of a step", TypeError, "steps", "integer")
def system_run_fraction(sc):
    sc.system.integrator.run(2.5)


# --- particles -----------------------------------------------------------------
@case("part.add(pos=[1, 2]): a 2-vector for a position", ValueError, "pos")
def part_pos_2vec(sc):
    sc.system.part.add(pos=[1, 2])


@case("part.add(pos='1 2 3'): a string for a position", TypeError, "pos")
def part_pos_string(sc):
    sc.system.part.add(pos="1 2 3")


@case("part.add(pos=[1, nan, 3])", ValueError, "pos", "finite")
def part_pos_nan(sc):
    sc.system.part.add(pos=[1, NAN, 3])


@case("part.add(pos=[inf, 2, 3])", ValueError, "pos", "finite")
def part_pos_inf(sc):
    sc.system.part.add(pos=[INF, 2, 3])


@case("part.add(pos=[[1, 2, 3], [1, 2]]): a ragged list of positions", TypeError, "pos", "numbers")
def part_pos_ragged(sc):
    sc.system.part.add(pos=[[1, 2, 3], [1, 2]])


@case("part.add(pos=..., mass=0)", ValueError, "mass")
def part_mass_zero(sc):
    sc.system.part.add(pos=[1, 2, 3], mass=0.0)


@case("part.add(pos=..., mass=-1)", ValueError, "mass")
def part_mass_negative(sc):
    sc.system.part.add(pos=[1, 2, 3], mass=-1.0)


@case("part.add(pos=..., type=-1)", ValueError, "type")
def part_type_negative(sc):
    sc.system.part.add(pos=[1, 2, 3], type=-1)


@case("part.add(pos=..., type=1.7): a fractional type", TypeError, "type", "integer")
def part_type_fraction(sc):
    sc.system.part.add(pos=[1, 2, 3], type=1.7)


@case("part.add(id=0, ...): an id already taken", ValueError, "id", "0")
def part_id_taken(sc):
    sc.system.part.add(id=0, pos=[1, 2, 3])


@case("part.add(pos=N x 3, mass=[1, -1]): one bad row of many (nothing added)", ValueError, "mass")
def part_bulk_one_bad_row(sc):
    sc.system.part.add(pos=[[1, 1, 1], [2, 2, 2]], mass=[1.0, -1.0])


@case("part.by_id(99): a particle that does not exist", IndexError, "99", "does not exist")
def part_missing_id(sc):
    sc.system.part.by_id(99).pos


@case("part.all().v = [[...], [nan, 0, 0]]: NaN in a slice assignment (nothing changed)", ValueError, "finite")
def part_slice_nan(sc):
    sc.system.part.all().v = [[0, 0, 0], [NAN, 0, 0]]


# --- interactions --------------------------------------------------------------
@case("soft_sphere.set_params(a=1, n=2, cutoff=-1)", ValueError, "cutoff")
def inter_soft_sphere_cutoff(sc):
    sc.system.non_bonded_inter[0, 0].soft_sphere.set_params(a=1.0, n=2.0, cutoff=-1.0)


@case("soft_sphere.set_params(a=nan, ...)", ValueError, "a", "finite")
def inter_soft_sphere_nan(sc):
    sc.system.non_bonded_inter[0, 0].soft_sphere.set_params(a=NAN, n=2.0, cutoff=1.0)


@case("soft_sphere.set_params(a='1', ...): a string", TypeError, "a", "number")
def inter_soft_sphere_string(sc):
    sc.system.non_bonded_inter[0, 0].soft_sphere.set_params(a="1", n=2.0, cutoff=1.0)


@case("non_bonded_inter[-1, 0]: a negative particle type", ValueError, "types", "0..1023")
def inter_type_negative(sc):
    sc.system.non_bonded_inter[-1, 0].soft_sphere.set_params(a=1.0, n=2.0, cutoff=1.0)


@case("HarmonicBond(k=-1, r_0=1)", ValueError, "k")
def bond_k_negative(sc):
    lbmd.interactions.HarmonicBond(k=-1.0, r_0=1.0)


@case("HarmonicBond(k=1, r_0='1')", TypeError, "r_0", "number")
def bond_r0_string(sc):
    lbmd.interactions.HarmonicBond(k=1.0, r_0="1")


@case("add_bond((bond, 42)): a bond to a particle that does not exist", ValueError, "42")
def bond_missing_partner(sc):
    b = lbmd.interactions.HarmonicBond(k=1.0, r_0=1.0)
    sc.system.bonded_inter.add(b)
    sc.system.part.by_id(0).add_bond((b, 42))


# --- shapes and constraints ----------------------------------------------------
@case("Wall(normal=[0, 0, 0])", ValueError, "normal")
def shape_wall_zero_normal(sc):
    lbmd.shapes.Wall(normal=[0, 0, 0], dist=1.0)


@case("Wall(normal=[0, 1]): a 2-vector", ValueError, "normal", "3 numbers")
def shape_wall_2vec(sc):
    lbmd.shapes.Wall(normal=[0, 1], dist=1.0)


@case("Sphere(radius=0)", ValueError, "radius")
def shape_sphere_zero(sc):
    lbmd.shapes.Sphere(center=[1, 1, 1], radius=0.0)


@case("Sphere(radius=-2)", ValueError, "radius")
def shape_sphere_negative(sc):
    lbmd.shapes.Sphere(center=[1, 1, 1], radius=-2.0)


@case("Sphere(center='middle')", TypeError, "center")
def shape_sphere_center_string(sc):
    lbmd.shapes.Sphere(center="middle", radius=1.0)


@case("Sphere(direction=2): direction is +1 or -1", ValueError, "direction")
def shape_sphere_direction(sc):
    lbmd.shapes.Sphere(center=[1, 1, 1], radius=1.0, direction=2)


@case("Cylinder(length=nan)", ValueError, "length", "finite")
def shape_cylinder_nan(sc):
    lbmd.shapes.Cylinder(center=[4, 4, 4], axis=[0, 0, 1], radius=2.0, length=NAN)


@case("sphere.radius = 5 after creation (would change the Python object only)", AttributeError, "radius")
def shape_set_after_creation(sc):
    lbmd.shapes.Sphere(center=[1, 1, 1], radius=1.0).radius = 5.0


@case("ShapeBasedConstraint(shape='wall'): not a shape", TypeError, "shape")
def constraint_not_shape(sc):
    lbmd.constraints.ShapeBasedConstraint(shape="wall", particle_type=1)


@case("constraints.add(c) twice (its force would count twice)", ValueError, "already")
def constraint_twice(sc):
    c = lbmd.constraints.ShapeBasedConstraint(shape=lbmd.shapes.Wall(normal=[0, 0, 1], dist=0.0),
                                              particle_type=1)
    sc.system.constraints.add(c)
    try:
        sc.system.constraints.add(c)
    finally:
        sc.system.constraints.remove(c)


# --- thermostats ---------------------------------------------------------------
@case("thermostat.set_langevin(kT=0, gamma=-1)", ValueError, "gamma")
def thermo_gamma_negative(sc):
    sc.system.thermostat.set_langevin(kT=0.0, gamma=-1.0)


@case("thermostat.set_langevin(kT=1, gamma=1) without a seed", ValueError, "seed")
def thermo_no_seed(sc):
    sc.system.thermostat.set_langevin(kT=1.0, gamma=1.0)


@case("thermostat.set_langevin(kT=nan, gamma=1)", ValueError, "kT", "finite")
def thermo_kt_nan(sc):
    sc.system.thermostat.set_langevin(kT=NAN, gamma=1.0)


@case("thermostat.set_lb(LB_fluid='lbf'): not a fluid", TypeError, "LB_fluid")
def thermo_lb_not_fluid(sc):
    sc.system.thermostat.set_lb(LB_fluid="lbf", gamma=1.0)


@case("thermostat.set_lb before system.actors.add(lbf)", ValueError, "add the fluid first")
def thermo_lb_fluid_not_added(sc):
    lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=0.5, tau=0.1)
    sc.system.thermostat.set_lb(LB_fluid=lbf, gamma=1.0)


@case("thermostat.set_lb(gamma=-1)", ValueError, "gamma", scene="fluid")
def thermo_lb_gamma_negative(sc):
    sc.system.thermostat.set_lb(LB_fluid=sc.lbf, gamma=-1.0)


# --- the fluid -----------------------------------------------------------------
def fluid(**kw):
    p = dict(agrid=1.0, dens=1.0, visc=0.5, tau=0.1)
    p.update(kw)
    return lbmd.lb.LBFluid(**p)


@case("LBFluid(agrid=0)", ValueError, "agrid", "> 0")
def lb_agrid_zero(sc):
    fluid(agrid=0.0)


@case("LBFluid(agrid=-1)", ValueError, "agrid", "> 0")
def lb_agrid_negative(sc):
    fluid(agrid=-1.0)


@case("LBFluid(visc='0.5'): a string", TypeError, "visc", "number")
def lb_visc_string(sc):
    fluid(visc="0.5")


@case("LBFluid(dens=nan)", ValueError, "dens", "finite")
def lb_dens_nan(sc):
    fluid(dens=NAN)


@case("LBFluid(tau=inf)", ValueError, "tau", "finite")
def lb_tau_inf(sc):
    fluid(tau=INF)


@case("LBFluid(ext_force_density=[0, 0]): a 2-vector", ValueError, "ext_force_density", "3 numbers")
def lb_force_2vec(sc):
    fluid(ext_force_density=[0, 0])


@case("LBFluid(collision='LBGK'): an unknown collision", ValueError, "collision", "MRT")
def lb_collision(sc):
    fluid(collision="LBGK")


@case("LBFluid(kT=1) without a seed", ValueError, "seed")
def lb_kt_no_seed(sc):
    fluid(kT=1.0)


@case("actors.add(LBFluid(agrid=3)) in a box of 8: box not a multiple of agrid", ValueError, "agrid", "does not divide")
def lb_box_not_multiple(sc):
    sc.system.actors.add(fluid(agrid=3.0))


@case("actors.add(LBFluid(tau=0.25)) with time_step 0.1: tau not a multiple of time_step",
      ValueError, "tau", "multiple")
def lb_tau_not_multiple(sc):
    sc.system.actors.add(fluid(tau=0.25))


@case("actors.add(lbf) on a System without a time step", ValueError, "time_step")
def lb_no_time_step(sc):
    s = lbmd.System(box_l=[4, 4, 4])
    s.actors.add(fluid())


@case("actors.add(lbf) twice", ValueError, "already", scene="fluid")
def lb_added_twice(sc):
    sc.system.actors.add(sc.lbf)


@case("actors.add(a second LBFluid)", ValueError, "already has", scene="fluid")
def lb_second_fluid(sc):
    sc.system.actors.add(fluid())


@case("lbf.agrid = 2 once the fluid exists", AttributeError, "agrid", scene="fluid")
def lb_change_agrid(sc):
    sc.lbf.agrid = 2.0


@case("system.box_l = [10, 10, 10] once the fluid exists", ValueError, "box_l", "fluid", scene="fluid")
def lb_change_box(sc):
    sc.system.box_l = [10.0, 10.0, 10.0]


@case("system.time_step = 0.03 once a fluid of tau 0.1 exists", ValueError, "tau", scene="fluid")
def lb_change_time_step(sc):
    sc.system.time_step = 0.03


@case("lbf[100, 0, 0]: a node outside the lattice", IndexError, "out of range", scene="fluid")
def lb_node_out_of_range(sc):
    sc.lbf[100, 0, 0].velocity


@case("lbf[0, 0, 0].density = -1", ValueError, "density", scene="fluid")
def lb_node_density_negative(sc):
    sc.lbf[0, 0, 0].density = -1.0


@case("lbf[0, 0, 0].velocity = [1, 2]: a 2-vector", ValueError, "velocity", "shape", scene="fluid")
def lb_node_velocity_2vec(sc):
    sc.lbf[0, 0, 0].velocity = [1.0, 2.0]


@case("lbf[0, 0, 0].vel = ...: a misspelt node property", AttributeError, "vel", scene="fluid")
def lb_node_misspelt(sc):
    sc.lbf[0, 0, 0].vel = [0.0, 0.0, 0.0]


@case("lbf.shape of a fluid not added to a system", RuntimeError, "actors.add")
def lb_not_added(sc):
    fluid().shape


@case("lbf.get_interpolated_velocity(...) of a fluid not added (no actor)", RuntimeError, "actors.add")
def lb_velocity_not_added(sc):
    fluid().get_interpolated_velocity([1, 1, 1])


@case("actors.add('lbf'): not an actor", TypeError, "not an actor")
def lb_add_not_actor(sc):
    sc.system.actors.add("lbf")


@case("actors.remove(lbf) of a fluid never added", ValueError, "not active")
def lb_remove_not_added(sc):
    sc.system.actors.remove(fluid())


@case("LBFluid(n_threads=100000): absurdly many threads", ValueError, "n_threads")
def lb_threads(sc):
    fluid(n_threads=100000)


@case("a coupled particle moved outside a non-periodic box (z = 7.5 in a box of 6)", lbmd.SimulationInstability,
      "particle 0", "non-periodic axis 2", "left the box")
def lb_particle_outside_box(sc):
    s = lbmd.System(box_l=[6, 6, 6], periodicity=[True, True, False])
    s.time_step = 0.1
    lbf = fluid()
    s.actors.add(lbf)
    s.part.add(pos=[3, 3, 3]).pos = [3, 3, 7.5]  # (part.add refuses it; a moved particle is caught by the run)
    s.thermostat.set_lb(LB_fluid=lbf, gamma=1.0)
    s.integrator.run(2)


# --- cells ---------------------------------------------------------------------
@case("OifCellType(nodes_file='missing.dat', ...): a mesh file that does not exist", ValueError,
      "missing.dat", "does not exist")
def cell_type_missing_file(sc):
    oif.OifCellType(sc.path("missing.dat"), SPHERE[1], system=sc.system)


@case("OifCellType(nodes_file=[...]): an array for a file name", TypeError, "nodes_file", "file name")
def cell_type_array_for_file(sc):
    oif.OifCellType(np.loadtxt(SPHERE[0]), SPHERE[1], system=sc.system)


@case("OifCellType(...) without system=", TypeError, "system")
def cell_type_no_system(sc):
    oif.OifCellType(*SPHERE)


@case("OifCellType(resize=(2, 2, -2))", ValueError, "resize", "positive")
def cell_type_resize_negative(sc):
    oif.OifCellType(*SPHERE, system=sc.system, resize=(2, 2, -2))


@case("OifCellType(resize=(2, 2)): a 2-vector", ValueError, "resize", "3 numbers")
def cell_type_resize_2vec(sc):
    oif.OifCellType(*SPHERE, system=sc.system, resize=(2, 2))


@case("OifCellType(ks=-0.01)", ValueError, "ks")
def cell_type_ks_negative(sc):
    oif.OifCellType(*SPHERE, system=sc.system, ks=-0.01)


@case("OifCellType(kb=nan)", ValueError, "kb", "finite")
def cell_type_kb_nan(sc):
    oif.OifCellType(*SPHERE, system=sc.system, kb=NAN)


@case("OifCellType(ks=0.01, kslin=0.01): both stretching laws", ValueError, "ks", "kslin")
def cell_type_ks_and_kslin(sc):
    oif.OifCellType(*SPHERE, system=sc.system, ks=0.01, kslin=0.01)


@case("OifCell(cell_type='rbc')", TypeError, "cell_type", "OifCellType", scene="cell")
def cell_wrong_type(sc):
    oif.OifCell(cell_type="rbc", particle_type=0, origin=[4, 4, 4])


@case("OifCell(origin=[4, 4]): a 2-vector", ValueError, "origin", "3 numbers", scene="cell")
def cell_origin_2vec(sc):
    oif.OifCell(cell_type=sc.cell_type, particle_type=0, origin=[4, 4])


@case("OifCell(origin=[nan, 4, 4])", ValueError, "origin", "finite", scene="cell")
def cell_origin_nan(sc):
    oif.OifCell(cell_type=sc.cell_type, particle_type=0, origin=[NAN, 4, 4])


@case("OifCell(particle_type=-1)", TypeError, "particle_type", scene="cell")
def cell_particle_type_negative(sc):
    oif.OifCell(cell_type=sc.cell_type, particle_type=-1, origin=[4, 4, 4])


@case("OifCell(particle_mass=0)", ValueError, "particle_mass", scene="cell")
def cell_mass_zero(sc):
    oif.OifCell(cell_type=sc.cell_type, particle_type=0, origin=[4, 4, 4], particle_mass=0.0)


@case("OifCell of a type wider than the periodic box (it would overlap its own image)", ValueError,
      "box", "periodic", scene="cell")
def cell_wider_than_box(sc):
    big = oif.OifCellType(*SPHERE, system=sc.system, resize=(9.0,) * 3, ks=0.01)
    oif.OifCell(cell_type=big, particle_type=1, origin=[8, 8, 8])


@case("OifCell placed over another cell", oif.OverlapWarning, "overlaps cell 0", scene="cell")
def cell_overlaps_cell(sc):
    c = oif.OifCell(cell_type=sc.cell_type, particle_type=1, origin=[9.0, 8.0, 8.0])
    c.mesh._parts.remove()  # the warning is the check; take the cell away again


@case("two cells placed at one origin (every node on the other's surface)", oif.OverlapWarning,
      "overlaps cell 0", scene="cell")
def cells_at_one_origin(sc):
    c = oif.OifCell(cell_type=sc.cell_type, particle_type=0, origin=[8.0, 8.0, 8.0])
    c.mesh._parts.remove()  # the warning is the check; take the cell away again


@case("part.add(pos=...) outside the box along an axis that is not periodic", ValueError, "pos",
      "outside the box", "not periodic")
def particle_outside_closed_box(sc):
    lbmd.System(box_l=[8.0] * 3, periodicity=[True, True, False]).part.add(pos=[1.0, 1.0, 9.5])


@case("actors.remove(lbf) while the thermostat couples the particles to it", SettingsWarning, "actors.remove",
      "no longer carried", "set_lb", scene="fluid_cell")
def fluid_removed_under_coupling(sc):
    sc.system.actors.remove(sc.lbf)
    sc.system.actors.add(sc.lbf)  # as it was, for the checks after the entry
    sc.system.thermostat.set_lb(LB_fluid=sc.lbf, gamma=1.0)


def cell_through(sc, walls, wall):
    """Places a cell through `wall` added to `walls` (constraints or
    lbboundaries), then takes both away again."""
    walls.add(wall)
    try:
        c = oif.OifCell(cell_type=sc.cell_type, particle_type=1, origin=[1.5, 3.0, 3.0])
        c.mesh._parts.remove()
    finally:
        walls.remove(wall)


@case("OifCell placed through a wall", oif.OverlapWarning, "constraint 0", "Wall", scene="cell")
def cell_in_wall(sc):
    cell_through(sc, sc.system.constraints, lbmd.constraints.ShapeBasedConstraint(
        shape=lbmd.shapes.Wall(normal=[1, 0, 0], dist=2.5), particle_type=5))


@case("OifCell placed through a wall that is a lattice boundary only", oif.OverlapWarning, "lattice boundary 0",
      "Wall", scene="fluid_cell")
def cell_in_lattice_wall(sc):
    cell_through(sc, sc.system.lbboundaries,
                 lbmd.lbboundaries.LBBoundary(shape=lbmd.shapes.Wall(normal=[1, 0, 0], dist=2.5)))


@case("two cell types of very different node density under one coupling gamma",
      SettingsWarning, "node density", scene="fluid")
def cell_types_density_one_gamma(sc):
    s = lbmd.System(box_l=[24, 12, 12])
    s.time_step = 0.1
    lbf = fluid()
    s.actors.add(lbf)
    fine = oif.OifCellType(*oif.mesh_files("sphere642"), system=s, resize=(2.0,) * 3, ks=0.01)
    coarse = oif.OifCellType(*SPHERE, system=s, resize=(3.0,) * 3, ks=0.01)
    cells = [oif.OifCell(cell_type=fine, particle_type=0, origin=[6, 6, 6]),  # held: checked
             oif.OifCell(cell_type=coarse, particle_type=1, origin=[17, 6, 6])]
    s.thermostat.set_lb(LB_fluid=lbf, gamma=0.05)
    s.integrator.run(10)  # the check comes with the first run of 10 steps or more
    return cells


def walled_channel(constraints=True, boundaries=True, coupled=True, contact=True, wall_type=5, cell_type=0):
    """A channel between two walls at y 1 and 11 with a fluid and one cell;
    the named parts left out or mixed up. Returns (system, kept objects)."""
    s = lbmd.System(box_l=[16, 12, 12])
    s.time_step = 0.1
    lbf = fluid()
    s.actors.add(lbf)
    for w in (lbmd.shapes.Wall(normal=[0, 1, 0], dist=1), lbmd.shapes.Wall(normal=[0, -1, 0], dist=-11)):
        if constraints:
            s.constraints.add(shape=w, particle_type=wall_type)
        if boundaries:
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=w))
    ct = oif.OifCellType(*SPHERE, system=s, resize=(2.0,) * 3, ks=0.01, kb=0.01, kal=0.01, kag=0.1, kv=0.1,
                         normal=True)
    cell = oif.OifCell(cell_type=ct, particle_type=cell_type, origin=[8, 6, 6])
    if contact and wall_type != cell_type:
        oif.set_contacts(s, ct, particle_types=cell_type, wall_types=[wall_type])
    if coupled:
        s.thermostat.set_lb(LB_fluid=lbf, gamma=ct.suggest_LBgamma(visc=0.5, dens=1.0))
    s.integrator.run(10)  # the check comes with the first run of 10 steps or more
    return s, cell


@case("cells in a fluid without thermostat.set_lb: the cells do not feel the fluid", SettingsWarning,
      "coupled to the fluid", "no drag", "set_lb")
def cells_not_coupled(sc):
    return walled_channel(coupled=False)


@case("walls added only as constraints, not as lattice boundaries: the fluid flows through them",
      SettingsWarning, "constraint 0", "flows through this wall", "LBBoundary")
def walls_only_constraints(sc):
    return walled_channel(boundaries=False)


@case("walls only as lattice boundaries, with cells: the cells feel no wall", SettingsWarning,
      "lattice boundary 0", "pass into it", "constraints.add")
def walls_only_lattice(sc):
    return walled_channel(constraints=False)


@case("a wall with no contact between its particle type and the cells'", SettingsWarning,
      "constraint 0", "feel nothing from this wall", "set_contacts")
def wall_without_contact(sc):
    return walled_channel(contact=False)


@case("a cell given the wall's particle type", SettingsWarning, "particle type 5", "same particle type")
def cell_with_wall_type(sc):
    return walled_channel(cell_type=5)


@case("a driving force far too large: the fluid passes the advised Mach number mid-run", SettingsWarning,
      "reached Mach", "lattice node", "after lattice update")
def fluid_too_fast(sc):
    s = lbmd.System(box_l=[8, 10, 4])
    s.time_step = 0.1
    lbf = fluid(ext_force_density=[0.5, 0, 0])  # Poiseuille peak speed 2.0: Mach 0.6
    s.actors.add(lbf)
    for w in (lbmd.shapes.Wall(normal=[0, 1, 0], dist=1), lbmd.shapes.Wall(normal=[0, -1, 0], dist=-9)):
        s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=w))
    s.integrator.run(100)  # the first check (Mach 0 at the start) is quiet: the watch tells
    return s


@case("System(box_l=[1e-4, 5e-5, 5e-5]): lengths in metres", ValueError, "box_l", "metres", "100 um")
def system_box_metres(sc):
    lbmd.System(box_l=[1e-4, 5e-5, 5e-5])


@case("LBFluid(agrid=1e-6): the lattice spacing in metres", ValueError, "agrid", "metres")
def fluid_agrid_metres(sc):
    fluid(agrid=1e-6)


@case("OifCellType(resize=(3.91e-6,) * 3): a cell's radius in metres", ValueError, "resize", "metres")
def cell_type_radius_metres(sc):
    oif.OifCellType(*oif.mesh_files("rbc374"), system=sc.system, resize=(3.91e-6,) * 3, ks=0.005)


@case("oif.scene_parameters(narrowest=12, ...): a channel width in um where metres are asked", ValueError,
      "narrowest", "metres", "1.2e-05 m")
def plan_narrowest_in_um(sc):
    oif.scene_parameters(narrowest=12, mean_speed=1e-3)


@case("oif.scene_parameters(..., accuracy=2): the error wanted in % where a fraction is asked", ValueError,
      "accuracy", "fraction")
def plan_accuracy_percent(sc):
    oif.scene_parameters(narrowest=12e-6, mean_speed=1e-3, accuracy=2)


@case("oif.scene_parameters(..., time_budget=10): a budget no accuracy fits", ValueError, "time_budget",
      "coarser accuracy", "shorter duration")
def plan_budget_too_small(sc):
    oif.scene_parameters(narrowest=12e-6, mean_speed=1e-3, duration=0.1, box=[100e-6, 40e-6, 14e-6], cells=20,
                         accuracy=0.05, time_budget=10)


@case("seed_cells(..., haematocrit=1.5)", ValueError, "haematocrit", "(0, 1)", scene="cell")
def seed_haematocrit(sc):
    oif.seed_cells(sc.system, sc.cell_type, haematocrit=1.5, seed=1)


@case("seed_cells(..., counts=2, haematocrit=0.1): both", TypeError, "exactly one", scene="cell")
def seed_counts_and_haematocrit(sc):
    oif.seed_cells(sc.system, sc.cell_type, counts=2, haematocrit=0.1, seed=1)


@case("seed_cells(..., counts=500): more cells than the box holds", oif.SeedingError, "cannot be placed",
      scene="cell")
def seed_too_many(sc):
    oif.seed_cells(sc.system, sc.cell_type, counts=500, seed=1)


@case("seed_cells(..., boundaries=['wall']): not a shape", TypeError, "boundaries", scene="cell")
def seed_boundary_not_shape(sc):
    oif.seed_cells(sc.system, sc.cell_type, counts=1, boundaries=["wall"], seed=1)


@case("seed_cells(..., rotation_axis=[0, 0, 0]): no direction", ValueError, "rotation_axis", "non-zero vector",
      scene="cell")
def seed_rotation_axis_zero(sc):
    oif.seed_cells(sc.system, sc.cell_type, counts=1, rotation_axis=[0, 0, 0], seed=1)


@case("system.box_l = [3.5, 3.5, 3.5] once a cell 4 wide exists (it would overlap its own periodic image)",
      ValueError, "box_l", "cell 0", scene="cell")
def cell_change_box(sc):
    sc.system.box_l = [3.5, 3.5, 3.5]


@case("OifCell wider than a non-periodic box along z (ESPResSo 4.1's OIF test builds one)",
      ValueError, "the cell spans z", "not periodic", "wider than the box", "porting.md")
def cell_wider_than_closed_box(sc):
    # (ESPResSo 4.1's test: a box 10 long in a non-periodic z, a cell 13 wide)
    s = lbmd.System(box_l=[12, 12, 3], periodicity=[True, True, False])
    ct = oif.OifCellType(*SPHERE, system=s, resize=(2.0,) * 3, ks=0.01)
    oif.OifCell(cell_type=ct, particle_type=0, origin=[6, 6, 1.5])


@case("system.periodicity = [True, True, False] with a cell across the box's z faces", ValueError,
      "periodicity", "cell 0", "not periodic")
def cell_change_periodicity(sc):
    s = lbmd.System(box_l=[20.0] * 3)
    ct = oif.OifCellType(*SPHERE, system=s, resize=(2.0,) * 3, ks=0.01)
    cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[10, 10, 1.0])
    try:
        s.periodicity = [True, True, False]
    finally:
        assert list(s.periodicity) == [True, True, True], "the refused periodicity was applied"
        del cell


@case("system.box_l shrunk along a non-periodic axis past a particle", ValueError, "box_l", "outside the box",
      "non-periodic z")
def box_shrunk_past_particle(sc):
    s = lbmd.System(box_l=[8.0] * 3, periodicity=[True, True, False])
    s.part.add(pos=[1.0, 1.0, 6.0])
    try:
        s.box_l = [8.0, 8.0, 5.0]
    finally:
        assert list(s.box_l) == [8.0, 8.0, 8.0], "the refused box was applied"


# --- mesh files ----------------------------------------------------------------
@case("an empty nodes file", ValueError, "nodes.dat", "no data")
def mesh_empty(sc):
    cell_type_from(sc, "", sphere_arrays()[1])


@case("a nodes file with two numbers on a line (ragged)", ValueError, "nodes.dat, line 3", "expected 3")
def mesh_ragged(sc):
    nodes, tris = sphere_arrays()
    text = "\n".join(" ".join(repr(x) for x in row) for row in nodes).split("\n")
    text[2] = "0.1 0.2"
    cell_type_from(sc, "\n".join(text) + "\n", tris)


@case("a triangles file with a word in it (non-numeric)", ValueError, "triangles.dat, line 5", "integers")
def mesh_non_numeric(sc):
    nodes, tris = sphere_arrays()
    text = [" ".join(map(str, r)) for r in tris]
    text[4] = "1 two 3"
    cell_type_from(sc, nodes, "\n".join(text) + "\n")


@case("a node coordinate 'nan' in the nodes file", ValueError, "nodes.dat, line 1", "finite")
def mesh_nan(sc):
    nodes, tris = sphere_arrays()
    nodes[0, 1] = NAN
    cell_type_from(sc, nodes, tris)


@case("a triangle naming node 999 of 162 (out of range)", ValueError, "triangles.dat, line 1", "out of range")
def mesh_id_out_of_range(sc):
    nodes, tris = sphere_arrays()
    tris[0, 0] = 999
    cell_type_from(sc, nodes, tris)


@case("a mesh with a triangle missing (an open surface)", ValueError, "triangles.dat", "open edge")
def mesh_open(sc):
    nodes, tris = sphere_arrays()
    cell_type_from(sc, nodes, tris[1:])


@case("an edge shared by three triangles (non-manifold)", ValueError, "more than two triangles")
def mesh_non_manifold(sc):
    nodes, tris = sphere_arrays()
    extra = np.array([[tris[0, 0], tris[0, 1], tris[5, 2]]])
    cell_type_from(sc, nodes, np.vstack([tris, extra]))


@case("one triangle turned the wrong way, check_orientation=False (inverted)", ValueError,
      "oriented opposite", "check_orientation")
def mesh_inverted_triangle(sc):
    nodes, tris = sphere_arrays()
    tris[7] = tris[7, [0, 2, 1]]
    cell_type_from(sc, nodes, tris, check_orientation=False)


@case("a surface pushed through itself (self-intersecting)", ValueError, "nodes.dat", "intersect")
def mesh_self_intersecting(sc):
    nodes, tris = sphere_arrays()
    i = int(np.argmax(nodes[:, 2]))
    nodes[i] = [0.05, 0.03, -1.5]  # the top node through the bottom
    cell_type_from(sc, nodes, tris)


@case("a triangle repeating a node (degenerate)", ValueError, "triangles.dat, line 1", "degenerate")
def mesh_degenerate(sc):
    nodes, tris = sphere_arrays()
    tris[0, 2] = tris[0, 0]
    cell_type_from(sc, nodes, tris)


@case("two nodes at the same place (duplicate node)", ValueError, "nodes.dat", "duplicates")
def mesh_duplicate_node(sc):
    nodes, tris = sphere_arrays()
    t = int(np.nonzero(tris == 0)[0][0])
    tris[t][tris[t] == 0] = len(nodes)  # that triangle uses a copy of node 0
    cell_type_from(sc, np.vstack([nodes, nodes[:1]]), tris)


@case("a node no triangle uses", ValueError, "nodes.dat", "not used")
def mesh_unused_node(sc):
    nodes, tris = sphere_arrays()
    cell_type_from(sc, np.vstack([nodes, [[5.0, 5.0, 5.0]]]), tris)


@case("two separate spheres in one mesh file", ValueError, "more than one connected surface")
def mesh_two_surfaces(sc):
    nodes, tris = sphere_arrays()
    cell_type_from(sc, np.vstack([nodes, nodes + 5.0]), np.vstack([tris, tris + len(nodes)]))


@case("a nodes.dat given without its triangles file", ValueError, "triangles_file")
def mesh_no_triangles_file(sc):
    oif.OifCellType(SPHERE[0], "", system=sc.system)


@case("a folder given as the nodes file", ValueError, "directory")
def mesh_directory(sc):
    oif.OifCellType(sc.tmp, SPHERE[1], system=sc.system)


# --- checkpoints ---------------------------------------------------------------
@case("checkpoint.load of a file that does not exist", lbmd.checkpoint.CheckpointError, "no such file")
def checkpoint_missing(sc):
    lbmd.checkpoint.load(sc.path("nothing.h5"))


@case("checkpoint.load of a file that is not a checkpoint (a text file)", lbmd.checkpoint.CheckpointError,
      "not a readable HDF5")
def checkpoint_foreign(sc):
    with open(sc.path("notes.h5"), "w") as f:
        f.write("not a checkpoint\n")
    lbmd.checkpoint.load(sc.path("notes.h5"))


@case("checkpoint.load of an HDF5 file written by something else", lbmd.checkpoint.CheckpointError,
      "not a PyOIF checkpoint")
def checkpoint_other_hdf5(sc):
    import h5py
    with h5py.File(sc.path("other.h5"), "w") as f:
        f["x"] = np.arange(3)
    lbmd.checkpoint.load(sc.path("other.h5"))


@case("checkpoint.load(system): a System for the path", TypeError, "path")
def checkpoint_path_system(sc):
    lbmd.checkpoint.load(sc.system)


@case("checkpoint.save(path, lbf): not a System as the second argument", TypeError, "system", scene="fluid")
def checkpoint_save_not_system(sc):
    lbmd.checkpoint.save(sc.path("x.h5"), sc.lbf)


@case("checkpoint.load of a truncated checkpoint (a copy cut short)", lbmd.checkpoint.CheckpointError,
      "truncated", scene="fluid")
def checkpoint_truncated(sc):
    lbmd.checkpoint.save(sc.path("c.h5"), sc.system, lbf=sc.lbf)
    with open(sc.path("c.h5"), "rb") as f, open(sc.path("cut.h5"), "wb") as g:
        g.write(f.read()[:2000])
    lbmd.checkpoint.load(sc.path("cut.h5"))


@case("checkpoint.save(path, system, f=lambda x: x): an object that cannot be saved", TypeError,
      "cannot save", "lambdas")
def checkpoint_save_lambda(sc):
    lbmd.checkpoint.save(sc.path("c.h5"), sc.system, f=lambda x: x)


# --- MPI -----------------------------------------------------------------------
@case("an error on one MPI rank only (e.g. `if lbmd.rank == 1: raise ...`): every rank ends within "
      "seconds, the traceback marked with the rank; an engine error met by one rank is raised on every rank "
      "(test_mpi_errors.py, which starts mpirun)", None, "test_error_on_rank_1_ends_all_ranks",
      "test_engine_error_on_one_rank_raised_on_every_rank")
def mpi_one_rank(sc):
    # the MPI cases need mpirun: they run in test_mpi_errors.py; here the
    # catalogue checks that they are there
    with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "test_mpi_errors.py")) as f:
        return f.read()


def markdown():
    rows = ["| # | what the user did | exception | the message says |", "| --- | --- | --- | --- |"]
    for k, c in enumerate(CASES, 1):
        exc = c.exc if isinstance(c.exc, tuple) else (c.exc,) if c.exc else ()
        names = " or ".join(f"`{e.__module__ + '.' if e.__module__ not in ('builtins',) else ''}{e.__name__}`"
                            for e in exc)
        gist = " ... ".join(f"'{g}'" for g in c.gist)
        if c.exc is None:  # the pointer to test_mpi_errors.py
            names = "the failing rank's own exception; every rank ends (`MPI_Abort`)"
            gist = "its traceback, each line marked `[rank R]`"
        rows.append(f"| {k} | {c.what.replace('|', '/')} | {names} | {gist} |")
    return "\n".join(rows)


class TestBadInput(unittest.TestCase):
    def check_usable(self, sc, before):
        after = sc.snapshot()
        for k in ("n", "dt", "actors", "constraints", "periodicity"):
            self.assertEqual(after[k], before[k], f"'{k}' changed by a refused input")
        np.testing.assert_array_equal(after["box"], before["box"])
        np.testing.assert_array_equal(after["pos"], before["pos"])
        sc.system.integrator.run(3)
        pos = sc.system.part.all().pos
        self.assertTrue(np.all(np.isfinite(pos)), "positions not finite after the mistake")
        self.assertEqual(len(pos), before["n"])
        if sc.lbf is not None:
            self.assertAlmostEqual(sc.lbf.total_mass(), before["mass"], delta=1e-9 * before["mass"])

    def test_catalogue(self):
        self.assertGreaterEqual(len([c for c in CASES if c.exc is not None]), 60)
        self.assertEqual(len({c.key for c in CASES}), len(CASES))
        for c in CASES:
            with self.subTest(entry=c.key, what=c.what), tempfile.TemporaryDirectory() as tmp:
                sc = Scene(c.scene, tmp)
                sc.system.integrator.run(1)  # the settings check of the first run is behind us
                before = sc.snapshot()
                is_warning = isinstance(c.exc, type) and issubclass(c.exc, Warning)
                if c.exc is None:  # tested elsewhere: fn returns the text that must name it
                    msg = c.fn(sc)
                elif is_warning:
                    with warnings.catch_warnings(record=True) as caught:
                        warnings.simplefilter("always")
                        c.fn(sc)
                    msgs = [str(w.message) for w in caught if issubclass(w.category, c.exc)]
                    self.assertTrue(msgs, f"{c.key}: no {c.exc.__name__}; got "
                                    f"{[str(w.message) for w in caught]}")
                    msg = msgs[0]
                else:
                    with self.assertRaises(c.exc) as cm:
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore")
                            c.fn(sc)
                    msg = str(cm.exception)
                for word in c.gist:
                    self.assertIn(word.lower(), msg.lower(), f"{c.key}: message {msg!r}")
                self.check_usable(sc, before)

    def test_load_beside_running_system(self):
        """Loading a checkpoint while a system runs is no mistake: load makes a
        new System; the running one goes on as it was (doc/bad-input.md)."""
        with tempfile.TemporaryDirectory() as tmp:
            sc = Scene("fluid", tmp)
            lbmd.checkpoint.save(sc.path("c.h5"), sc.system, lbf=sc.lbf)
            sc.system.integrator.run(2)
            before = sc.snapshot()
            ns = lbmd.checkpoint.load(sc.path("c.h5"))
            self.assertIsNot(ns.system, sc.system)
            self.assertAlmostEqual(ns.system.time, 0.0)
            self.check_usable(sc, before)
            ns.system.integrator.run(2)
            self.assertAlmostEqual(ns.system.time, 0.2)


if __name__ == "__main__":
    if "--markdown" in sys.argv:
        print(markdown())
    else:
        unittest.main()
