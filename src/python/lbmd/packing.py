"""The engine's packing kernels, for cell models (oif.pack_cells builds on
them): a rigid-body packer of triangulated shapes and the exact check of
deformed meshes. Shapes are lbmd shapes (lbmd.shapes)."""
import numpy as np

from . import _lbmd


def _cores(owner, shapes):
    from .shapes import Shape
    out = []
    for i, s in enumerate(shapes):
        if not isinstance(s, Shape):
            raise TypeError(f"{owner}: parameter 'boundaries' item {i} must be an lbmd shape, got "
                            f"{type(s).__name__}")
        out.append(s._core)
    return out


class RigidPacker(_lbmd.RigidPacker):
    """Force-biased growth of rigid bodies against each other's level sets
    and the boundaries' signed distances (doc/oif.md, packing):
    add_type(nodes, triangles, spacing), add_boundary(shape), set_bodies(types,
    centres, quaternions), run(settings) -> dict, check(settings) -> dict,
    centres(), rotations()."""

    def add_boundary(self, shape):
        """A wall the bodies stay clear of (an lbmd shape)."""
        super().add_boundary(_cores("RigidPacker.add_boundary", [shape])[0])


def check_meshes(nodes, first_node, types, triangles, boundaries, settings, search):
    """The exact check of deformed cells before they are made: nodes of
    other cells inside a cell (winding numbers), the smallest node distance
    between cells and to the boundaries (lbmd shapes). nodes: all cells'
    nodes stacked; first_node: each cell's first row and the end; types: each
    cell's index into triangles (one outward-oriented (m, 3) array per type);
    settings: the packer's settings dict; search: the neighbour search
    range. Returns a dict (nodes_inside_cells, min_node_distance,
    min_wall_distance, ...)."""
    return _lbmd.check_meshes(np.ascontiguousarray(nodes, dtype=float), list(first_node), list(types),
                              list(triangles), _cores("check_meshes", boundaries), settings, search)
