"""PLACEHOLDER: filled by the lattice-Boltzmann work."""


class LBFluid:
    pass
