"""The command line: ``python -m pdfem [command] ...``.

Each command is a module of this package with ``add_parser(subparsers)`` and ``run(args)``.
With no command, the default scene runs. An :class:`~pdfem.errors.InputError` anywhere ends
the program with its message on one line and exit status 2; a
:class:`~pdfem.errors.SimulationError` with exit status 3. Never a traceback for either.
"""

import argparse
import importlib
import os
import sys

from pdfem import sigterm
from pdfem.errors import InputError, SimulationError

# Third-party packages pdfem needs at run time (pyproject.toml's dependencies, and matplotlib
# for the figures): one missing means an environment that is not the project's
DEPENDENCIES = ("numpy", "numba", "mpi4py", "h5py", "meshio", "matplotlib", "llvmlite")

COMMANDS = ("run", "prepare", "sweep", "analyse", "hotspots", "export", "material", "bench",
            "study")


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as InputError (one line, exit 2)."""

    def error(self, message):
        raise InputError(f"{self.prog}: {message}")

    def _get_values(self, action, arg_strings):
        # argparse drops a "--" value (--strain=--) and hands the option an empty list
        if action.option_strings and action.nargs is None and arg_strings == ["--"]:
            self.error(f"argument {'/'.join(action.option_strings)}: expected one argument")
        return super()._get_values(action, arg_strings)


def _parser():
    p = _Parser(prog="pdfem", description="Parallel Discrete Finite Element Method for "
                "shock compression of granular media.")
    sub = p.add_subparsers(dest="command", parser_class=_Parser)
    for name in COMMANDS:
        importlib.import_module(f"pdfem.cli.{name}").add_parser(sub)
    return p


def _rank():
    """This process's rank; an error found before MPI started does not start it (under
    mpirun the launcher's environment tells the rank)."""
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None:
        return mpi.COMM_WORLD.rank
    for var in ("OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"):
        if os.environ.get(var, "").isdigit():
            return int(os.environ[var])
    return 0


def main(argv=None):
    """Entry point; returns the exit status."""
    argv = sys.argv[1:] if argv is None else argv
    try:
        args = _parser().parse_args(argv or ["run"])
        # Only a run turns a SIGTERM into a checkpoint; any other command dies of it
        if args.command != "run":
            sigterm.release()
        mod = importlib.import_module(f"pdfem.cli.{args.command}")
        return mod.run(args) or 0
    except (InputError, SimulationError) as exc:
        # Raised on every rank together (input checks and step guards are collective)
        if _rank() == 0:
            print(f"pdfem: error: {exc}", file=sys.stderr, flush=True)
        return exc.exit_status
    except ModuleNotFoundError as exc:
        if (exc.name or "").split(".")[0] not in DEPENDENCIES:
            _abort(exc)
            raise
        print(f"pdfem: error: the package {exc.name.split('.')[0]} is not installed for "
              f"{sys.executable}: activate the project's environment (. .venv/bin/activate) "
              "or install it (bash jobs/install.sh)", file=sys.stderr, flush=True)
        return 2
    except Exception as exc:
        _abort(exc)
        raise


def _abort(exc):
    """An unexpected exception on one rank: print it and abort every rank (no hang)."""
    import traceback

    traceback.print_exc(file=sys.stderr)
    rank = _rank()
    print(f"pdfem: internal error on rank {rank}: {type(exc).__name__}: {exc}",
          file=sys.stderr, flush=True)
    try:
        from mpi4py import MPI

        if MPI.COMM_WORLD.size > 1:
            MPI.COMM_WORLD.Abort(1)
    except ImportError:
        pass
