"""Errors a user can act on: the command line prints the message on one line and exits 2."""


class InputError(Exception):
    """Bad input: a scene key, a file, a command-line argument. Exit status 2, no traceback."""

    exit_status = 2


class SceneError(Exception):
    """A bad scene value: ``str(exc)`` is ``"key.path: what is wrong"`` on one line (the scene
    parser prefixes the file name and raises :class:`InputError`)."""

    def __init__(self, path, msg):
        super().__init__(f"{path}: {msg}" if path else msg)


class SimulationError(Exception):
    """A run that cannot continue (unstable contact, inverted element, non-finite value).

    Exit status 3; the message names the step, time, grain/element ids and the check.
    """

    exit_status = 3
