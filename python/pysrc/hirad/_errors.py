"""The exceptions of hirad.

Every error of a solve is a :class:`HiradError` with the message the ``hirad`` command line
would print (the file and line:column of a fault in a ``.hir`` or ``.obj`` file, the byte
offset in a ``.hirb``). Bad arguments to ``hirad.Scene`` methods are plain ``ValueError``.
"""


class HiradError(Exception):
    """A solve failed: the run could not complete (the CLI's exit status 4), or the base of
    the more precise classes below."""


class InputError(HiradError):
    """The scene is missing, unreadable or invalid (the CLI's exit status 3)."""


class UsageError(HiradError, ValueError):
    """A setting is wrong: out of range, or a workspace (``memory``) too small for the
    solve (the CLI's exit status 2). Also a ``ValueError``."""


class Cancelled(HiradError):
    """The progress callback returned ``False``: the solve stopped."""


class HiradWarning(UserWarning):
    """A solve's warning (a loader's note on the scene, a power balance off by more than
    1 %), or its verdict when the numbers are not right (not converged, power balance off by
    more than 5 %): the results are returned all the same, as the CLI writes its files."""
