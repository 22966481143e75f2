"""oif: the object-in-fluid cell model on the lbmd engine, with the classes
and keywords of PyOIF (ESPResSo 4.2's ``object_in_fluid``), so that
``import object_in_fluid as oif`` ports as ``import oif``.

- ``oif.OifCellType`` / ``oif.OifCell``: cell templates and cells,
- ``oif.Mesh`` and the views FixedPoint, PartPoint, Edge, Triangle, Angle,
  ThreeNeighbors,
- ``oif.oif_utils``: PyOIF's helper functions and VTK output of shapes (the
  ones ESPResSo 4.2 exports at package level, ``oif.norm``,
  ``oif.vec_distance``, ..., are here too),
- ``oif.mesh_files(name)``: the shipped meshes (spheres and Evans-Fung
  red blood cells, see ``oif/meshes/README.md``),
- ``oif.seed_cells``: random non-overlapping placement of many cells,
- ``oif.pack_cells``: cells packed to a haematocrit of 0.45, at their
  reference volume and surface (force-biased growth of rigid cells, then,
  where rigid cells jam, deformable ones swollen into place),
- ``oif.fluid_volume``: the volume of a region outside boundary shapes
  (what a haematocrit is a share of),
- ``oif.contact_settings`` / ``oif.set_contacts``: the advised
  hard_contact between cells and between cells and walls,
- ``oif.CellFlow``: cells leaving at an outlet and entering at an inlet
  (a haematocrit, a rate, or recycled), between runs,
- ``oif.stretch_cell``: the optical-tweezers stretch of a red blood cell
  (Mills et al. 2004), equilibrium diameters against force,
- ``oif.CellSeries``: VTK XML time series of cells (``.vtp`` steps and a
  ``.pvd`` collection) for ParaView.
"""
import os as _os

from .oif_classes import (FixedPoint, PartPoint, Edge, Triangle, Angle, ThreeNeighbors, Mesh,  # noqa: F401
                          OifCellType, OifCell, OverlapWarning, CellDamage, update_damage, DAMAGE_AREA_STRAIN)
from . import oif_utils  # noqa: F401
# the helpers ESPResSo 4.2's object_in_fluid exports at package level
from .oif_utils import (custom_str, get_triangle_normal, norm, vec_distance, area_triangle,  # noqa: F401
                        angle_btw_triangles, discard_epsilon, oif_neo_hookean_nonlin,
                        oif_calc_stretching_force, oif_calc_linear_stretching_force,
                        oif_calc_bending_force, oif_calc_local_area_force,
                        oif_calc_global_area_force, oif_calc_volume_force,
                        output_vtk_rhomboid, output_vtk_cylinder, output_vtk_pore, output_vtk_lines)
from .seeding import seed_cells, SeedingError, fluid_volume  # noqa: F401
from .packing import pack_cells, PackingError, PackedCells, covering_radius  # noqa: F401
from . import contacts  # noqa: F401
from .contacts import contact_settings, set_contacts  # noqa: F401
from .flow_through import CellFlow  # noqa: F401
from .scene_plan import scene_parameters, ScenePlan  # noqa: F401
from .compound import add_nucleus, CellCluster, BiCluster  # noqa: F401
from . import stretching  # noqa: F401
from .stretching import stretch_cell  # noqa: F401
from .vtk_series import CellSeries  # noqa: F401

MESH_DIR = _os.path.join(_os.path.dirname(__file__), "meshes")


def available_meshes():
    """Names of the shipped meshes (e.g. 'rbc374', 'sphere642')."""
    names = [f[:-len("nodes.dat")] for f in _os.listdir(MESH_DIR) if f.endswith("nodes.dat")]
    return sorted(names, key=lambda s: (s.rstrip("0123456789"), int(s[len(s.rstrip("0123456789")):] or 0)))


def mesh_files(name):
    """(nodes_file, triangles_file) of a shipped mesh, e.g. mesh_files('rbc374')."""
    nodes = _os.path.join(MESH_DIR, f"{name}nodes.dat")
    if not _os.path.isfile(nodes):
        raise ValueError(f"oif.mesh_files: no shipped mesh '{name}'; available: {', '.join(available_meshes())}")
    return nodes, _os.path.join(MESH_DIR, f"{name}triangles.dat")


__all__ = ["FixedPoint", "PartPoint", "Edge", "Triangle", "Angle", "ThreeNeighbors", "Mesh", "OifCellType", "OverlapWarning",
           "OifCell", "oif_utils", "custom_str", "get_triangle_normal", "norm", "vec_distance", "area_triangle",
           "angle_btw_triangles", "discard_epsilon", "oif_neo_hookean_nonlin", "oif_calc_stretching_force",
           "oif_calc_linear_stretching_force", "oif_calc_bending_force", "oif_calc_local_area_force",
           "oif_calc_global_area_force", "oif_calc_volume_force", "output_vtk_rhomboid", "output_vtk_cylinder", "output_vtk_pore",
           "output_vtk_lines", "seed_cells", "SeedingError", "fluid_volume", "pack_cells", "PackingError", "PackedCells", "covering_radius",
           "contacts", "contact_settings", "set_contacts", "CellFlow", "scene_parameters", "ScenePlan", "CellDamage", "update_damage", "DAMAGE_AREA_STRAIN", "add_nucleus", "CellCluster", "BiCluster", "stretching", "stretch_cell", "CellSeries", "mesh_files", "available_meshes", "MESH_DIR"]
