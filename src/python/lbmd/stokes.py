"""Stokes drag of a sphere in a periodic box (a simple cubic array).

A sphere of radius a in a cubic periodic box of side L, in Stokes flow
with U the mean (superficial) velocity of the fluid relative to the
spheres, i.e. the volume flux per area, feels the drag

    F = 6 pi eta a U / K(c),    c = 4 pi a^3 / (3 L^3),

K(c) = 1 - 1.7601 c^(1/3) + c - 1.5593 c^2 + 3.9799 c^(8/3) - 3.0734 c^(10/3)
(Hasimoto, J. Fluid Mech. 5, 317 (1959), the first four terms; Sangani &
Acrivos, Int. J. Multiphase Flow 8, 343 (1982), eq. 4.7 and their Table,
the two next). The series is good to about 1 % up to c ~ 0.2.

    >>> round(periodic_drag_factor(4 * math.pi / 3 / 125), 4)   # a = L / 5
    0.4647
"""
import math
import numbers


def _volume_fraction(name, c):
    if isinstance(c, bool) or not isinstance(c, numbers.Real) or not 0 <= c < 0.5:
        raise ValueError(f"{name}: 'volume_fraction' must be a number in [0, 0.5) (the series of a dilute "
                         f"simple cubic array), got {c!r}")
    return float(c)


def periodic_drag_factor(volume_fraction):
    """K(c): the Stokes drag of a sphere in the simple cubic array is that of
    the lone sphere divided by K (module docstring)."""
    c = _volume_fraction("periodic_drag_factor", volume_fraction)
    x = c ** (1.0 / 3.0)
    return 1 - 1.7601 * x + x ** 3 - 1.5593 * x ** 6 + 3.9799 * x ** 8 - 3.0734 * x ** 10


def sphere_volume_fraction(radius, box_length):
    """c = 4 pi a^3 / (3 L^3) of a sphere of radius a in a cube of side L."""
    for name, v in (("radius", radius), ("box_length", box_length)):
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not v > 0:
            raise ValueError(f"sphere_volume_fraction: '{name}' must be a positive number, got {v!r}")
    return 4.0 * math.pi * radius ** 3 / (3.0 * box_length ** 3)


def periodic_stokes_drag(dynamic_viscosity, radius, mean_velocity, box_length):
    """F = 6 pi eta a U / K(c) of a sphere of radius a in a cubic periodic
    box of side L, U the superficial velocity of the fluid past it."""
    if isinstance(dynamic_viscosity, bool) or not isinstance(dynamic_viscosity, numbers.Real) \
            or not dynamic_viscosity > 0:
        raise ValueError(f"periodic_stokes_drag: 'dynamic_viscosity' must be a positive number, "
                         f"got {dynamic_viscosity!r}")
    c = sphere_volume_fraction(radius, box_length)
    return 6.0 * math.pi * dynamic_viscosity * radius * mean_velocity / periodic_drag_factor(c)


def hydrodynamic_radius(drag, dynamic_viscosity, mean_velocity, box_length):
    """The radius a of the sphere whose periodic Stokes drag at this U and L
    is `drag`: 6 pi eta a U / K(c(a)) = F, solved by bisection (the drag
    grows with a; a fixed-point iteration on a = F K / (6 pi eta U) does not
    converge at c ~ 0.03 and above)."""
    if not drag > 0 or not mean_velocity > 0:
        raise ValueError(f"hydrodynamic_radius: 'drag' and 'mean_velocity' must be positive, got {drag!r} "
                         f"and {mean_velocity!r}")
    lo = 0.0
    hi = box_length * (3.0 * 0.45 / (4.0 * math.pi)) ** (1.0 / 3.0)  # volume fraction 0.45
    if periodic_stokes_drag(dynamic_viscosity, hi, mean_velocity, box_length) < drag:
        raise ValueError(f"hydrodynamic_radius: the drag {drag!r} needs a sphere filling more than 0.45 of "
                         f"the box, outside the series")
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if periodic_stokes_drag(dynamic_viscosity, mid, mean_velocity, box_length) < drag:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)
