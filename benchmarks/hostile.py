"""Hostile inputs (issue 37, exhaustion): the big cases whose work must grow linearly with their size.

Each generator takes ``(n, seed)`` like the others (the seed is unused: the texts are fixed shapes):

- ``generate_unknown_instances``: a system with n ``connect`` lines naming unknown instances, 2n
  errors (E101), each line padded with a comment to about 100 characters (the text renderer once split
  the whole file again for every diagnostic);
- ``generate_junk_line``: a component opened, then n words on its one line (error recovery once went on
  through every error on a line, as only one is reported per line);
- ``generate_one_core``: n timer tasks on one core at one priority (every response once held the ids of
  all the others: n² names);
- ``generate_trigger_chain``: an n-hop chain of tasks over 8 cores, each triggered by the one before, at
  falling priorities (the causal-path walks once went through all that lies upstream of every task).
"""
from __future__ import annotations

COMPONENT = "component C {\n  out o : T\n  task K {\n    produces o\n    wcet 1 ms\n  }\n}\n"


def generate_unknown_instances(n: int, seed: int = 1) -> str:
    lines = "".join(f"  connect nope{k}.o -> nada{k}.i  // {'x' * 60}\n" for k in range(n))
    return COMPONENT + "system S {\n  core c0\n" + lines + "}\n"


def generate_junk_line(n: int, seed: int = 1) -> str:
    return "component C { " + "x " * n + "\n"


def generate_one_core(n: int, seed: int = 1) -> str:
    instances = "".join(f"  instance i{k} : C on c {{ task T priority 1 timer 1 s }}\n" for k in range(n))
    return "component C {\n  task T {\n    wcet 1 us\n  }\n}\nsystem S {\n  core c\n" + instances + "}\n"


def generate_trigger_chain(n: int, seed: int = 1, cores: int = 8) -> str:
    component = ("component P {\n  in i : M\n  out o : M\n  task Run {\n    reads i optional\n    produces o\n"
                 "    bcet 1 us\n    wcet 2 us\n  }\n}\n")
    lines = [f"  core c{c}\n" for c in range(cores)]
    lines += [f"  instance p{k} : P on c{k % cores} {{ task Run priority {n - k} "
              f"{'trigger i' if k else 'timer 10 ms'} }}\n" for k in range(n)]
    lines += [f"  connect p{k - 1}.o -> p{k}.i\n" for k in range(1, n)]
    lines.append("  chain c: " + " -> ".join(f"p{k}.o" for k in range(n)) + " {\n    reaction_time <= 1000 s\n  }\n")
    return component + "system S {\n" + "".join(lines) + "}\n"


def render_diagnostics(text: str) -> tuple[int, int]:
    """Load ``text`` and render its diagnostics as ``verify check`` does: (diagnostics, lines shown)."""
    import verify
    from verify.outputs.rendering import render_all_text

    result = verify.load_text(text, "hostile.vfy")
    return len(result.diagnostics), render_all_text(result.diagnostics, result.sources).count("\n")


def recover(text: str) -> int:
    """Parse ``text`` (Lark's error path): the syntax errors reported."""
    from verify.frontend.parse import parse_source

    return len(parse_source(text, "hostile.vfy").diagnostics)
