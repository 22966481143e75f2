"""Open faces of the lattice-Boltzmann fluid: velocity inlets and pressure
outlets (``lbf.open_boundaries``).

    inlet = lbmd.open_boundaries.VelocityInlet(face="x-", profile="poiseuille", flow_rate=Q)
    outlet = lbmd.open_boundaries.PressureOutlet(face="x+", density=dens)
    lbf.open_boundaries.add(inlet)
    lbf.open_boundaries.add(outlet)

A face is a side of the box: "x-" (the node plane x = 0), "x+" (the last
plane), "y-", "y+", "z-", "z+". The lattice is periodic, so the face opposite an
open face is either open too (an inlet and an outlet, or two outlets at
different densities: a pressure-driven flow) or closed by walls where it
meets the open face across the periodic edge (a T-junction's side outlet
on y+ above a channel floor on y-); any number of faces may be open. After every lattice update
the face planes take the populations of the non-equilibrium extrapolation
scheme (Guo, Zheng & Shi, Chin. Phys. 11, 366 (2002); second order): the
equilibrium at the face's density and velocity plus the non-equilibrium part
of the next node inward. A velocity inlet prescribes the velocity of each
face node (the density follows the flow); a pressure outlet the density,
i.e. the pressure p = c_s^2 rho with c_s^2 = agrid^2 / (3 tau^2) (the
velocity follows the flow). Boundary (solid) nodes on a face are left alone.

Inlet profiles (velocities in MD units, along the face's inward normal):

- ``profile="plug"``: the same velocity at every fluid node of the face;
- ``profile="poiseuille"``: the fully developed laminar profile of the
  face's cross-section (any shape: the 2D Poisson equation lap u = -1 is
  solved on the face's fluid nodes, zero on the walls midway between a fluid
  and a solid node, as the halfway bounce-back puts them), so that the flow
  enters developed;
- ``values=array``: a given profile, the face's node shape (n_a, n_b) or
  (n_a, n_b, 3) (then the full velocity vector);

scaled by exactly one of ``mean_velocity`` (over the fluid nodes of the
face), ``max_velocity`` or ``flow_rate`` (volume per time). With
``flow_rate`` the face's velocities are also scaled, update by update, by a
slow controller until the flow through the node plane next to the face is
the flow rate asked: where the face meets walls the scheme alone delivers a
little less (3.7 % in a duct 10 nodes high, less in wider channels).
"""
import numpy as np

from .validation import Param, ParameterObject, non_negative, positive

_FACES = {"x-": (0, False), "x+": (0, True), "y-": (1, False), "y+": (1, True), "z-": (2, False),
          "z+": (2, True)}


def _face(owner, value):
    if value not in _FACES:
        raise ValueError(f"{owner}: parameter 'face' must be one of {', '.join(_FACES)}, got {value!r}")
    return _FACES[value]


def _plane_axes(axis):
    return [d for d in range(3) if d != axis]


def poiseuille_profile(mask):
    """The solution of lap u = -1 (lattice spacing 1) on the True nodes of
    the 2D boolean `mask`, u = 0 on walls midway to the False nodes; the
    plane is periodic where no wall closes it. Raises ValueError when some
    fluid region touches no wall (the profile would be unbounded)."""
    import scipy.sparse
    import scipy.sparse.linalg
    mask = np.asarray(mask, dtype=bool)
    na, nb = mask.shape
    index = -np.ones(mask.shape, dtype=np.int64)
    index[mask] = np.arange(mask.sum())
    rows, cols, vals = [], [], []
    diag = np.zeros(mask.sum())
    ia, ib = np.nonzero(mask)
    me = index[ia, ib]
    for da, db in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        ja, jb = (ia + da) % na, (ib + db) % nb
        other = index[ja, jb]
        fluid = other >= 0
        # a fluid neighbour: -u_j; a wall midway: u there is -u_i (linear to
        # zero at the midpoint), so the diagonal grows by one more
        rows.append(me[fluid])
        cols.append(other[fluid])
        vals.append(-np.ones(fluid.sum()))
        diag += np.where(fluid, 1.0, 2.0)
    rows.append(me)
    cols.append(me)
    vals.append(diag)
    n = int(mask.sum())
    matrix = scipy.sparse.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                     shape=(n, n))
    if n == 0:
        raise ValueError("the face has no fluid node")
    # a region without any wall neighbour has a singular operator
    n_walls = np.zeros(n)
    for da, db in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        n_walls += index[(ia + da) % na, (ib + db) % nb] < 0
    import scipy.sparse.csgraph
    _, labels = scipy.sparse.csgraph.connected_components(matrix, directed=False)
    touched = np.bincount(labels, weights=n_walls)
    if np.any(touched == 0):
        raise ValueError("a fluid region of the face touches no wall: a Poiseuille profile needs walls "
                         "around the inlet (use profile='plug')")
    u = scipy.sparse.linalg.spsolve(matrix.tocsc(), np.ones(n))
    out = np.zeros(mask.shape)
    out[mask] = u
    return out


class VelocityInlet(ParameterObject):
    """A face with a prescribed velocity (see the module's docstring)."""

    _params = [Param("face", "object", cls=str, doc="x-, x+, y-, y+, z- or z+"),
               Param("profile", "object", "plug", cls=str,
                     check=(lambda s: s in ("plug", "poiseuille", "values"), "'plug', 'poiseuille' or 'values'")),
               Param("mean_velocity", "float", None, check=non_negative),
               Param("max_velocity", "float", None, check=non_negative),
               Param("flow_rate", "float", None, check=non_negative),
               Param("values", "object", None)]

    def _validate(self):
        _face("VelocityInlet", self.face)
        given = [k for k in ("mean_velocity", "max_velocity", "flow_rate") if self._values[k] is not None]
        if self.profile == "values" or self._values["values"] is not None:
            if self._values["values"] is None:
                raise ValueError("VelocityInlet: profile='values' needs parameter 'values'")
            values = np.asarray(self._values["values"], dtype=float)
            if values.ndim not in (2, 3) or (values.ndim == 3 and values.shape[2] != 3):
                raise ValueError("VelocityInlet: parameter 'values' must have the face's node shape "
                                 f"(n_a, n_b) or (n_a, n_b, 3), got shape {values.shape}")
            if not np.all(np.isfinite(values)):
                raise ValueError("VelocityInlet: parameter 'values' must be finite")
            self._values["values"] = values
            self._values["profile"] = "values"
            if given:
                raise ValueError("VelocityInlet: give 'values' alone (not with " + ", ".join(given) + ")")
        elif len(given) != 1:
            raise ValueError("VelocityInlet: give exactly one of mean_velocity, max_velocity, flow_rate "
                             f"(got {', '.join(given) or 'none'})")

    def face_velocities(self, fluid):
        """The velocity (MD units) of every node of the face plane, shape
        (n_a, n_b, 3), from the fluid's boundary flags."""
        axis, high = _face("VelocityInlet", self.face)
        shape = fluid.shape
        a, b = _plane_axes(axis)
        index = [slice(None)] * 3
        index[axis] = shape[axis] - 1 if high else 0
        flags = np.asarray(fluid[tuple(index)].boundary)
        fluid_nodes = flags == 0
        out = np.zeros((shape[a], shape[b], 3))
        inward = -1.0 if high else 1.0
        if self.profile == "values":
            values = self.values
            if values.shape[:2] != (shape[a], shape[b]):
                raise ValueError(f"VelocityInlet: 'values' has shape {values.shape[:2]}, the face "
                                 f"{self.face} has {shape[a]} x {shape[b]} nodes")
            if values.ndim == 3:
                out[:] = values
            else:
                out[..., axis] = inward * values
            out[~fluid_nodes] = 0.0
            return out
        if self.profile == "plug":
            shape_function = fluid_nodes.astype(float)
        else:
            try:
                shape_function = poiseuille_profile(fluid_nodes)
            except ValueError as e:
                raise ValueError(f"VelocityInlet (face {self.face}): {e}") from None
        n_fluid = fluid_nodes.sum()
        if n_fluid == 0:
            raise ValueError(f"VelocityInlet: the face {self.face} has no fluid node")
        mean = shape_function[fluid_nodes].mean()
        if self.mean_velocity is not None:
            speed = self.mean_velocity / mean
        elif self.max_velocity is not None:
            speed = self.max_velocity / shape_function.max()
        else:  # flow_rate: volume per time through the fluid nodes' area
            speed = self.flow_rate / (n_fluid * fluid.agrid ** 2) / mean
        out[..., axis] = inward * speed * shape_function
        return out


class PressureOutlet(ParameterObject):
    """A face with a prescribed density (pressure p = c_s^2 rho)."""

    _params = [Param("face", "object", cls=str, doc="x-, x+, y-, y+, z- or z+"),
               Param("density", "float", check=positive, doc="density at the face (MD units)")]

    def _validate(self):
        _face("PressureOutlet", self.face)


class OpenBoundaries:
    """``lbf.open_boundaries``: add / remove / clear / iterate; the faces are
    sent to the fluid as a whole (both faces of an axis must be open when a
    run starts)."""

    def __init__(self, fluid):
        self._fluid = fluid
        self._list = []

    def add(self, face):
        if not isinstance(face, (VelocityInlet, PressureOutlet)):
            raise TypeError("open_boundaries.add: expected a VelocityInlet or PressureOutlet, got "
                            f"{type(face).__name__}")
        if any(_face("", f.face) == _face("", face.face) for f in self._list):
            raise ValueError(f"open_boundaries.add: the face {face.face} is already open")
        self._list.append(face)
        try:
            self._apply()
        except Exception:
            self._list.remove(face)
            self._apply()
            raise
        return face

    def remove(self, face):
        if not any(f is face for f in self._list):
            raise ValueError("open_boundaries.remove: this face was not added")
        self._list = [f for f in self._list if f is not face]
        self._apply()

    def clear(self):
        self._list = []
        self._apply()

    def __iter__(self):
        return iter(list(self._list))

    def __len__(self):
        return len(self._list)

    def __repr__(self):
        return f"OpenBoundaries({self._list!r})"

    def _apply(self):
        """Sends the faces to the C++ fluid, when it exists (whether a face
        open alone has its opposite face closed is checked at the run's
        start and in mass_flux, once the walls are flagged)."""
        core = self._fluid._core
        if core is None:
            return
        self._walls = self._wall_signature()
        specs = []
        for f in self._list:
            axis, high = _face("", f.face)
            if isinstance(f, PressureOutlet):
                specs.append((axis, high, True, [], f.density, 0.0))
            else:
                specs.append((axis, high, False, f.face_velocities(self._fluid).ravel().tolist(), 0.0,
                              f.flow_rate or 0.0))
        # the flow-rate controllers keep their gains when the faces stay
        # (profiles made again after the walls changed)
        faces = [(axis, high, pressure) for axis, high, pressure, *_ in specs]
        gains = list(core.open_boundary_gains()) if faces == self.__dict__.get("_faces") else None
        core.set_open_boundaries(specs)
        self._faces = faces
        if gains is not None and len(gains) == len(specs):
            core.set_open_boundary_gains(gains)

    def _wall_signature(self):
        """Which boundaries the system has (the inlet profiles follow them)."""
        system = self._fluid._system
        return tuple(id(b) for b in system.lbboundaries) if system is not None else ()

    def _before_run(self):
        """At a run's start: each face's opposite face open or closed, and
        inlet profiles made again if the walls changed since."""
        self.check_complete()
        if self._wall_signature() != self.__dict__.get("_walls"):
            self._apply()

    def check_complete(self):
        """ValueError naming a face whose opposite face is neither open nor
        closed by walls where the two meet across the periodic edge
        (collective: the lattice is flagged first)."""
        if not self._list or self._fluid._system is None:
            return  # (checked when the fluid is in a system and runs)
        self._fluid._system.prepare()
        leaks = self._fluid._checked_core().open_seam_leaks()
        for f, n in zip(self._list, leaks):
            if n:
                other = f.face[0] + ("-" if f.face[1] == "+" else "+")
                raise ValueError(
                    f"open boundary {f.face}: the lattice is periodic along {f.face[0]}, and the opposite "
                    f"face {other} is neither open nor closed where it meets {f.face}: {n} fluid nodes of "
                    f"{other} would take what {f.face} streams across the periodic edge. Open {other} too "
                    f"(a VelocityInlet or PressureOutlet) or close it with a wall there (an LBBoundary "
                    f"covering the {other} plane wherever {f.face} is open)")

    def mass_flux(self, face):
        """Mass per time entering the fluid through an open face (negative:
        leaving); collective under MPI."""
        self.check_complete()
        for i, f in enumerate(self._list):
            if f is face or f.face == face:
                return float(self._fluid._checked_core().open_boundary_mass_flux(i))
        raise ValueError(f"open_boundaries.mass_flux: {face!r} is not an open face of this fluid")


# -- the ports of a device ---------------------------------------------------------
class Port(tuple):
    """A run of fluid nodes on a side face of the box: ``(face, first,
    last)``, first and last the node indices along the face's other
    in-plane axis (x for the faces y-, y+; y for x-, x+)."""
    __slots__ = ()

    def __new__(cls, face, first, last):
        return super().__new__(cls, (face, int(first), int(last)))

    def __getnewargs__(self):  # (pickle, copy: the three fields, not one tuple)
        return tuple(self)

    face = property(lambda self: self[0])
    first = property(lambda self: self[1])
    last = property(lambda self: self[2])

    def __repr__(self):
        return f"Port({self.face!r}, {self.first}, {self.last})"


def find_ports(fluid, z=None):
    """The ports of a device extruded along z: per side face (x-, x+, y-,
    y+), each run of fluid nodes on the node plane `z` (a node index;
    default the middle plane), as Port(face, first, last). A face with no
    fluid node is wall; two runs on one face are two ports (two branches
    ending on one side). Collective (reads the lattice's flags)."""
    owner = "open_boundaries.find_ports"
    shape = fluid.shape
    if z is None:
        z = shape[2] // 2
    if isinstance(z, bool) or not isinstance(z, (int, np.integer)) or not 0 <= z < shape[2]:
        raise ValueError(f"{owner}: parameter 'z' must be a node index in 0..{shape[2] - 1}, got {z!r}")
    flags = np.asarray(fluid[:, :, int(z)].boundary)
    ports = []
    for face, line in (("x-", flags[0, :]), ("x+", flags[-1, :]), ("y-", flags[:, 0]), ("y+", flags[:, -1])):
        fluid_nodes = np.flatnonzero(line == 0)
        if len(fluid_nodes):
            for run in np.split(fluid_nodes, np.flatnonzero(np.diff(fluid_nodes) > 1) + 1):
                ports.append(Port(face, run[0], run[-1]))
    return ports


def port_region(port, box_l, depth, heights, agrid=1.0):
    """The box (lo, hi corners) of a port's run of nodes, from depth[0] to
    depth[1] inside its face, over the z range `heights`: where oif.CellFlow
    puts cells in (an inlet region) or takes them out (an outlet region)."""
    face, first, last = port
    axis, other = (0, 1) if face[0] == "x" else (1, 0)
    box_l = np.asarray(box_l, dtype=float)
    lo, hi = np.array([0.0, 0.0, float(heights[0])]), np.array([0.0, 0.0, float(heights[1])])
    lo[other], hi[other] = first * agrid, (last + 1) * agrid
    near, far = float(depth[0]), float(depth[1])
    if face[1] == "-":
        lo[axis], hi[axis] = near, far
    else:
        lo[axis], hi[axis] = box_l[axis] - far, box_l[axis] - near
    return lo, hi


def port_flow(fluid, port):
    """Volume per time out of the device through a port's run of nodes, on
    the node plane two spacings inside its face (MD units); negative where
    the flow goes in. Collective."""
    face, first, last = port
    axis = 0 if face[0] == "x" else 1
    index = 2 if face[1] == "-" else fluid.shape[axis] - 3
    plane = fluid[index, :, :] if axis == 0 else fluid[:, index, :]
    u = np.asarray(plane.velocity)[first:last + 1, :, axis]
    return float(u.sum()) * fluid.agrid ** 2 * (-1.0 if face[1] == "-" else 1.0)
