"""PLACEHOLDER: filled by the lattice-Boltzmann work."""


class LBBoundaries:
    def __init__(self, system):
        self._system = system
