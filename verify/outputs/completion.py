"""Shell completion scripts (``verify completion bash|zsh|fish``), written from the argument parser.

What a script completes is read off the parser that ``verify.cli`` builds: the commands, each command's
options (an option with choices completes them: ``--format``, ``--objective`` does not), its
positional choices (``gen ros1``) and, where a positional is a path, file names. ``explain`` completes
the diagnostic codes. The scripts complete ``verify`` and the ``synth`` and ``prove`` commands (the
same as ``verify synth`` and ``verify prove``). Nothing runs Python while completing: the scripts are
plain shell, so completion costs no start-up time.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass

__all__ = ["SHELLS", "script"]

SHELLS = ("bash", "zsh", "fish")
#: the commands a console script of their own also provides (pyproject.toml, [project.scripts])
ALIASES = ("synth", "prove")


@dataclass(frozen=True)
class Option:
    flags: tuple[str, ...]
    takes_value: bool
    choices: tuple[str, ...]
    help: str


@dataclass(frozen=True)
class Command:
    name: str
    help: str
    options: tuple[Option, ...]
    #: the choices of the first positional that has some (``gen TARGET``, ``explain CODE``), else ()
    words: tuple[str, ...]


def _options(parser: argparse.ArgumentParser) -> tuple[Option, ...]:
    return tuple(Option(tuple(a.option_strings), a.nargs != 0, tuple(str(c) for c in a.choices or ()),
                        " ".join((a.help or "").split()))
                 for a in parser._actions if a.option_strings and a.help != argparse.SUPPRESS)


def commands(parser: argparse.ArgumentParser) -> tuple[tuple[Option, ...], tuple[Command, ...]]:
    """The top-level options and every command, as the parser has them."""
    from ..core.codes import CODES

    found: list[Command] = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help or "" for a in action._choices_actions}
            for name, sub in action.choices.items():
                words = next((tuple(str(c) for c in a.choices) for a in sub._actions
                              if not a.option_strings and a.choices), ())
                if name == "explain":
                    words = tuple(CODES)
                found.append(Command(name, " ".join(helps.get(name, "").split()), _options(sub), words))
    return _options(parser), tuple(found)


def script(shell: str, parser: argparse.ArgumentParser) -> str:
    """The completion script for ``shell`` (one of ``SHELLS``)."""
    top, cmds = commands(parser)
    if shell == "fish":
        return _fish(top, cmds)
    text = _bash(top, cmds)
    if shell == "zsh":  # (zsh runs bash's completion functions through bashcompinit)
        return "#compdef verify synth prove\nautoload -U +X bashcompinit && bashcompinit\n" + text
    return text


def _quote(words: list[str] | tuple[str, ...]) -> str:
    return " ".join(words)


def _bash(top: tuple[Option, ...], cmds: tuple[Command, ...]) -> str:
    lines = ["# bash completion for verify, synth and prove (verify completion bash)",
             "_verify_complete() {",
             '  local cur="${COMP_WORDS[COMP_CWORD]}" prev="${COMP_WORDS[COMP_CWORD-1]}" cmd="" i',
             '  case "${COMP_WORDS[0]##*/}" in synth|prove) cmd="${COMP_WORDS[0]##*/}" ;; esac',
             '  if [[ -z "$cmd" ]]; then',
             "    for ((i = 1; i < COMP_CWORD; i++)); do",
             '      case "${COMP_WORDS[i]}" in -*) ;; *) cmd="${COMP_WORDS[i]}"; break ;; esac',
             "    done",
             "  fi",
             '  if [[ -z "$cmd" ]]; then',
             f'    COMPREPLY=($(compgen -W "{_quote([c.name for c in cmds] + [f for o in top for f in o.flags])}"'
             ' -- "$cur"))',
             "    return",
             "  fi",
             '  case "$cmd" in']
    for c in cmds:
        flags = [f for o in c.options for f in o.flags]
        lines.append(f"    {c.name})")
        lines.append('      case "$prev" in')
        for o in c.options:
            if o.takes_value:
                values = f'COMPREPLY=($(compgen -W "{_quote(o.choices)}" -- "$cur"))' if o.choices else \
                    'COMPREPLY=($(compgen -f -- "$cur"))'
                lines.append(f"        {'|'.join(o.flags)}) {values}; return ;;")
        lines.append("      esac")
        lines.append(f'      if [[ "$cur" == -* ]]; then COMPREPLY=($(compgen -W "{_quote(flags)}" -- "$cur"))')
        if c.words:
            lines.append(f'      else COMPREPLY=($(compgen -W "{_quote(c.words)}" -- "$cur") $(compgen -f -- "$cur"))')
        else:
            lines.append('      else COMPREPLY=($(compgen -f -- "$cur"))')
        lines.append("      fi ;;")
    lines += ["  esac", "}", "complete -o filenames -F _verify_complete verify synth prove", ""]
    return "\n".join(lines)


def _fish_text(text: str) -> str:
    return "'" + text.replace("\\", "\\\\").replace("'", "\\'") + "'"


def _fish_option(prefix: str, o: Option) -> str:
    spec = " ".join(f"-l {f[2:]}" if f.startswith("--") else f"-s {f[1:]}" for f in o.flags)
    value = f" -x -a {_fish_text(' '.join(o.choices))}" if o.choices else (" -r -F" if o.takes_value else "")
    return f"{prefix} {spec}{value} -d {_fish_text(o.help[:80])}"


def _fish(top: tuple[Option, ...], cmds: tuple[Command, ...]) -> str:
    names = " ".join(c.name for c in cmds)
    lines = ["# fish completion for verify, synth and prove (verify completion fish)",
             "complete -c verify -f"]
    lines += [f"complete -c verify -n 'not __fish_seen_subcommand_from {names}' -a {c.name} "
              f"-d {_fish_text(c.help[:80])}" for c in cmds]
    lines += [_fish_option(f"complete -c verify -n 'not __fish_seen_subcommand_from {names}'", o) for o in top]
    for c in cmds:
        targets = [f"complete -c verify -n '__fish_seen_subcommand_from {c.name}'"]
        if c.name in ALIASES:
            targets.append(f"complete -c {c.name}")
        for prefix in targets:
            lines += [_fish_option(prefix, o) for o in c.options]
            if c.words:
                lines.append(f"{prefix} -a {_fish_text(' '.join(c.words))}")
            lines.append(f"{prefix} -F")
    return "\n".join(lines) + "\n"
