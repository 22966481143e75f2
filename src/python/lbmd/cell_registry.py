"""The cells a cell model builds in a System, without lbmd knowing the model.

lbmd is the engine: particles, bonds, shapes, the fluid. A cell model (the
``oif`` package) builds cells out of them and registers each one here
(``register(cell)``); lbmd reads them back through ``system.cells`` for what
the engine itself checks about cells:

- a change of ``box_l`` or ``periodicity`` that a cell would not fit
  (``cell.check_fits``);
- the cells' lines of ``system.check_settings()`` (the cell class's
  ``settings_check``, called once per class with its cells);
- the run summary's cell count (lbmd.progress).

So lbmd never imports a cell model (testsuite/python/test_layering.py fails
on such an import), and a cell model uses lbmd's public API only.

A registered cell provides:

``system``
    the lbmd.System it is in;
``cell_id``
    an int, the order in which ``system.cells`` lists the cells;
``is_live()``
    False once its particles are gone (removed at an outlet, say);
``check_fits(box, periodic)``
    raises ValueError naming the problem when the cell would not fit a box
    of these lengths and periodicity;
``settings_check`` (on its class)
    ``f(system, cells, fluid, gamma, langevin, report)`` appends
    ``lbmd.settings_check.Setting`` lines for ``cells`` (the live cells of
    this class in ``system``) to ``report``; ``fluid`` is the active LBFluid
    or None, ``gamma`` the coupling's friction, ``langevin`` the Langevin
    thermostat's.

The registry holds weak references: a cell the script no longer holds is
forgotten with it (its particles stay in the System, as particles).
"""
import weakref

_CELLS = weakref.WeakSet()
_PROTOCOL = ("system", "cell_id", "is_live", "check_fits", "settings_check")


def register(cell):
    """Add a cell (see the module's docstring for what it provides)."""
    missing = [name for name in _PROTOCOL if not hasattr(cell, name)]
    if missing:
        raise TypeError(f"cell_registry.register: a {type(cell).__name__} is no cell: it lacks "
                        f"{', '.join(missing)} (lbmd.cell_registry's docstring lists what a cell provides)")
    _CELLS.add(cell)


def unregister(cell):
    """Forget a cell (nothing happens when it was not registered)."""
    _CELLS.discard(cell)


def cells_of(system):
    """The live registered cells of system, by cell_id (a tuple)."""
    out = [c for c in list(_CELLS) if c.system is system and c.is_live()]
    return tuple(sorted(out, key=lambda c: c.cell_id))


def settings_checks(system):
    """[(settings_check, cells)]: one per cell class present in system, in
    the order of the first cell of each class."""
    groups = {}
    for c in cells_of(system):
        check = type(c).settings_check
        groups.setdefault(check, []).append(c)
    return list(groups.items())
