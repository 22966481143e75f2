"""Older ESPResSo names kept as aliases, so that scripts written for
ESPResSo <= 4.1 (and PyOIF scripts of that era) run after the import rename.

Each alias works like the current name and warns once per name per process
with ``OldNameWarning`` (a DeprecationWarning: shown for calls from a script's
own ``__main__``, or with ``python -W default``; silence it with
``warnings.simplefilter("ignore", lbmd.OldNameWarning)``). The list is in
doc/porting.md.
"""
import warnings


class OldNameWarning(DeprecationWarning):
    """An ESPResSo <= 4.1 name was used; the message names its current form."""


_warned = set()


def warn_old_name(old, new, stacklevel=3):
    """Warn once per ``old`` that it is an older name of ``new``."""
    if old in _warned:
        return
    _warned.add(old)
    warnings.warn(f"{old} is the ESPResSo <= 4.1 name of {new}; it works, but use {new}",
                  OldNameWarning, stacklevel=stacklevel)
