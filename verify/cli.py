"""The command line: the argument parser, built from the commands (``verify.commands``), and ``main``.

Every command lives in its own module under ``verify.commands``; the options every command that reads
a model shares (FILE, ``--format`` with the choices ``verify.outputs`` registers for the command's
result, ``--root``, ``--include``, ``--system``) are added here. The exit codes are those of
``verify.commands.common``.
"""
from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable
from types import ModuleType

from .commands import COMMANDS, command
from .commands.common import EXIT_INTERNAL, EXIT_INVALID, EXIT_OK

__all__ = ["main", "prove_main", "synth_main"]


def _model_options(p: argparse.ArgumentParser, module: ModuleType) -> None:
    from .outputs import formats

    if getattr(module, "FILES", False):
        p.add_argument("file", metavar="FILE", nargs="+", help="a .vfy file (imports are followed) or a directory "
                       "of them; `-`: standard input")
    else:
        p.add_argument("file", metavar="FILE", help="the .vfy file (imports are followed); `-`: standard input")
    choices = getattr(module, "FORMATS", None) or formats(module.RESULT)
    p.add_argument("--format", choices=choices, default=choices[0], action=_FormatGiven,
                   help=getattr(module, "FORMAT_HELP", "output format"))
    p.set_defaults(format_given=False)
    p.add_argument("--root", metavar="DIR", help="the project root: imports must stay inside it (default: "
                   "the `root` of [tool.verify] in pyproject.toml, else the directory of FILE)")
    p.add_argument("--include", metavar="DIR", action="append", default=[],
                   help="a library directory imports may also come from (repeatable)")
    if module.SYSTEM:
        p.add_argument("--system", metavar="NAME", help="the system to use when the file holds several")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="verify", description="Timing verification for component-based "
                                     "robotics software: check, analyze, synthesize and prove.")
    parser.add_argument("--version", action=_Version, help="print the version and those of the libraries, and exit")
    _color_option(parser, "auto")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        module = command(name)
        p = sub.add_parser(name, help=module.HELP, description=getattr(module, "DESCRIPTION", module.HELP))
        _color_option(p, argparse.SUPPRESS)  # (after the command too; given there, it wins)
        if getattr(module, "PARSER", False):  # (a command about the command line itself: `completion`)
            p.set_defaults(parser=parser)
        if hasattr(module, "add_leading_arguments"):  # (positionals before FILE: `gen TARGET FILE`)
            module.add_leading_arguments(p)
        if module.MODEL:
            _model_options(p, module)
        module.add_arguments(p)
        p.set_defaults(run=name)
    return parser


def _color_option(p: argparse.ArgumentParser, default: str) -> None:
    from .outputs.colour import CHOICES

    p.add_argument("--color", choices=CHOICES, default=default,
                   help="colour diagnostics: auto (on a terminal, unless NO_COLOR is set; the default), always, "
                        "never")


class _FormatGiven(argparse.Action):
    """``--format`` that records it was given (``graph -o OUT`` otherwise takes OUT's extension)."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: object,
                 option_string: str | None = None) -> None:
        setattr(namespace, self.dest, values)
        namespace.format_given = True


def _runner(name: str) -> Callable[[argparse.Namespace], int]:
    def run(args: argparse.Namespace) -> int:
        return int(command(name).run(args))

    run.__name__ = f"cmd_{name}"
    return run


# ``cmd_NAME`` runs command NAME; ``main`` looks it up here when it runs, so that a test may replace one
for _name in COMMANDS:
    globals()[f"cmd_{_name}"] = _runner(_name)


def _run(name: str, args: argparse.Namespace) -> int:
    return int(globals()[f"cmd_{name}"](args))


def main(argv: list[str] | None = None) -> int:
    try:
        args = _parser().parse_args(argv)
        from .outputs.colour import choose

        choose(args.color)
        return _run(args.run, args)
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:  # the reader went away (`verify explain E101 | head`): not an error of ours
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_OK
    except SystemExit as exit_:
        return int(exit_.code) if isinstance(exit_.code, int) else EXIT_INVALID
    except Exception as err:  # the last line of defence: never a traceback for the user
        if os.environ.get("VERIFY_DEBUG"):
            raise
        from .core.sanitize import shown

        print(f"internal error: {type(err).__name__}: {shown(str(err))}\n"
              "This is a bug in verify; please report it with the input file. "
              "Set VERIFY_DEBUG=1 to see the traceback.", file=sys.stderr)
        return EXIT_INTERNAL


class _Version(argparse.Action):
    """``--version``: ``version_text()`` as it is (argparse's own action re-wraps it to the terminal)."""

    def __init__(self, option_strings: list[str], dest: str, help: str | None = None) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, help=help)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: object,
                 option_string: str | None = None) -> None:
        print(version_text())
        parser.exit()


def version_text() -> str:
    """What ``--version`` prints: verify's version, and those of Python and of the libraries whose
    behaviour its results depend on (Lark's parse tables, Z3's solver and resource counts)."""
    from importlib.metadata import PackageNotFoundError, version

    from . import __version__

    def of(dist: str) -> str:
        try:
            return version(dist)
        except PackageNotFoundError:
            return "not installed"

    return (f"verify {__version__} (distribution verify-timing; Python {sys.version.split()[0]}, "
            f"lark {of('lark')}, z3-solver {of('z3-solver')}, networkx {of('networkx')})")


def _command_main(command_name: str) -> None:
    argv = sys.argv[1:]
    sys.exit(main(argv if argv == ["--version"] else [command_name, *argv]))


def synth_main() -> None:
    """The ``synth`` console script: ``synth FILE`` is ``verify synth FILE``."""
    _command_main("synth")


def prove_main() -> None:
    """The ``prove`` console script: ``prove FILE`` is ``verify prove FILE``."""
    _command_main("prove")
