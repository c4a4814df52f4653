"""One error family for everything a user can get wrong.

The library raises these; the CLI prints ``str(err)`` on one line and exits with ``err.exit_code``.
Anything else escaping the library is a bug, not a user error.
"""


class ChoreoError(Exception):
    """Base class: a problem with the user's input or environment, described in one line."""

    exit_code = 1


class InputError(ChoreoError):
    """An input file is missing, unreadable, malformed or of an unsupported kind."""

    exit_code = 2


class AudioError(InputError):
    """An audio file cannot be decoded or is unusable (empty, too short, silent)."""


class MotionFormatError(InputError):
    """A motion file is malformed, truncated, or uses a skeleton we cannot map to SMPL-24."""


class ParameterError(ChoreoError):
    """A value passed to a function or command is out of range or inconsistent."""

    exit_code = 2


class OutputError(ChoreoError):
    """An output cannot be written (missing or read-only folder, unknown format)."""

    exit_code = 3


class DatasetError(InputError):
    """A dataset folder does not have the layout its reader expects."""


class ChoreoNote(UserWarning):
    """Something choreo did with an input that the user should know (a channel ignored, data
    dropped): the CLI prints it as one ``note:`` line on stderr; from Python it is a warning."""
