"""The advised contacts between cells and between cells and walls:
``hard_contact`` (lbmd.interactions.HardContactInteraction), a repulsion
that diverges as the gap closes, with the offset chosen from the meshes so
that no finite squeeze pushes a node through a membrane
(doc/interactions.md, "hard_contact"; the measurements in doc/accuracy.md,
"Contacts").

``oif.contact_settings(cell_types)`` gives the parameters, and
``oif.set_contacts(system, cell_types, particle_types, wall_types)`` sets
them for every pair of cell types and every cell type with every wall type.
"""
import numpy as np

#: the advised force scale a (nN), exponent n and gap range (um) of
#: hard_contact, measured with the contacts chart (doc/accuracy.md): under a
#: push of 2 nN per cell at haematocrit 0.05-0.45 no node enters another cell
CONTACT_A = 0.01
CONTACT_N = 1.0
CONTACT_CUTOFF = 0.5
#: the packer's clearance beyond the contact's offset (um): a packed scene
#: starts with every gap at least a few times the contact's guard gap
PACKING_MARGIN = 0.04


def _types(cell_types):
    from .oif_classes import OifCellType
    types = [cell_types] if isinstance(cell_types, OifCellType) else list(cell_types)
    if not types or not all(isinstance(t, OifCellType) for t in types):
        raise TypeError("contact_settings: parameter 'cell_types' must be an OifCellType or a list of them")
    return types


def contact_offset(cell_types):
    """The offset that makes hard_contact uncrossable for these cell types:
    the largest covering radius of their relaxed meshes (oif.packing
    .covering_radius), rounded up to 0.01 um."""
    from .packing import covering_radius
    return float(np.ceil(max(covering_radius(t) for t in _types(cell_types)) * 100.0) / 100.0)


def contact_settings(cell_types):
    """The advised hard_contact parameters: dict with 'cell' (between cells
    of these types) and 'wall' (between their nodes and a wall; walls are
    exact surfaces, so no offset), each a dict of set_params keywords."""
    offset = contact_offset(cell_types)
    cell = dict(a=CONTACT_A, n=CONTACT_N, cutoff=CONTACT_CUTOFF, offset=offset)
    wall = dict(a=CONTACT_A, n=CONTACT_N, cutoff=CONTACT_CUTOFF, offset=0.0)
    return {"cell": cell, "wall": wall}


def guard_gap(a, time_step, node_mass, n=CONTACT_N, cutoff=CONTACT_CUTOFF):
    """The gap below which hard_contact's stiffness outruns the time step
    (k dt^2 / m = 1, k = a n cutoff^n / h^(n+1); doc/interactions.md): a
    run that starts with a gap below it stops at once with contact_overrun."""
    return float((a * n * cutoff ** n * time_step ** 2 / node_mass) ** (1.0 / (n + 1.0)))


def packing_clearance(cell_types, scale=1.0, time_step=None, node_mass=None):
    """The packer's clearance (oif.pack_cells): the contact's offset plus
    PACKING_MARGIN, or, given the run's time step and node mass, plus twice
    the guard gap of the advised contact at `scale` (set_contacts) where
    that is more: a scene with stiffened contacts and light nodes (the
    flagship at 27x: guard gap 0.05 um) needs its cells packed further
    apart than PACKING_MARGIN."""
    margin = PACKING_MARGIN
    if time_step is not None and node_mass is not None:
        margin = max(margin, 2.0 * guard_gap(CONTACT_A * scale, time_step, node_mass))
    return contact_offset(cell_types) + margin


def check_scale(owner, scale):
    """The contacts' force scale factor as a float, or ValueError naming `owner`."""
    if isinstance(scale, (bool, np.bool_)) or not isinstance(scale, (int, float, np.floating)) or not scale > 0:
        raise ValueError(f"{owner}: parameter 'scale' must be a number > 0, got {scale!r}")
    return float(scale)


def set_contacts(system, cell_types, particle_types, wall_types=(), scale=1.0):
    """Sets the advised hard_contact between every pair of the cells'
    particle types (including a type with itself: different cells of one
    type) and between every cell particle type and every wall type; returns
    the settings (contact_settings). scale multiplies the force scale a:
    where a scene stiffens its membranes to keep the capillary number at a
    faster flow, the contacts stiffen alike (the same gaps under the same
    relative load)."""
    scale = check_scale("set_contacts", scale)
    settings = contact_settings(cell_types)
    for k in settings.values():
        k["a"] *= float(scale)
    ptypes = sorted({int(t) for t in np.atleast_1d(particle_types)})
    walls = sorted({int(t) for t in np.atleast_1d(wall_types)}) if len(np.atleast_1d(wall_types)) else []
    for i, t1 in enumerate(ptypes):
        for t2 in ptypes[i:]:
            system.non_bonded_inter[t1, t2].hard_contact.set_params(**settings["cell"])
        for w in walls:
            system.non_bonded_inter[t1, w].hard_contact.set_params(**settings["wall"])
    return settings
