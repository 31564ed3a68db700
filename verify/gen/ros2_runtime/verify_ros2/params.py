"""The configuration a process reads from its ROS 2 parameters (config/parameters.yaml, specs/codegen.md
§3): nested keys joined by dots, times exact in ns as "N" or "N/D"."""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any


class ConfigError(Exception):
    """A missing or malformed parameter (the process stops, naming it)."""


def nested(flat: dict[str, Any]) -> dict[str, Any]:
    """``{"a.b": 1}`` as ``{"a": {"b": 1}}``."""
    out: dict[str, Any] = {}
    for key, value in flat.items():
        parts = key.split(".")
        node = out
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = value
    return out


def ns(table: dict[str, Any], key: str, where: str) -> Fraction:
    if key not in table:
        raise ConfigError(f"parameter {where}.{key} is missing")
    try:
        return Fraction(str(table[key]))
    except (ValueError, ZeroDivisionError) as err:
        raise ConfigError(f"parameter {where}.{key} is not a time in ns (\"N\" or \"N/D\"): {table[key]!r}") from err


def integer(table: dict[str, Any], key: str, where: str) -> int:
    value = table.get(key)
    if not isinstance(value, int) or isinstance(value, bool):
        raise ConfigError(f"parameter {where}.{key} is missing or not an integer: {value!r}")
    return value


def text(table: dict[str, Any], key: str, where: str, default: str | None = None) -> str:
    value = table.get(key, default)
    if not isinstance(value, str):
        raise ConfigError(f"parameter {where}.{key} is missing or not a string: {value!r}")
    return value


@dataclass(frozen=True)
class Role:
    """A task's part in a chain (specs/codegen.md §5)."""

    chain: str
    position: int
    source: str  # the in-port of the hop before ("": the chain's first task)
    target: str  # the out-port of the hop after ("": the chain's last task)


@dataclass(frozen=True)
class TaskConfig:
    task: str  # "instance.Task"
    activation: str  # "timer", "trigger" or "sporadic"
    priority: int
    period: Fraction = Fraction(0)
    phase: Fraction = Fraction(0)
    trigger: str = ""
    prescaler: int = 1
    min_gap: Fraction = Fraction(0)
    roles: tuple[Role, ...] = ()


def task_config(task: str, table: dict[str, Any]) -> TaskConfig:
    where = f"tasks.{task}"
    activation = text(table, "activation", where)
    priority = integer(table, "priority", where)
    roles = tuple(Role(chain, integer(r, "position", f"{where}.roles.{chain}"), text(r, "from", where, ""),
                       text(r, "to", where, ""))
                  for chain, r in sorted(table.get("roles", {}).items()))
    if activation == "timer":
        phase = ns(table, "phase_ns", where) if "phase_ns" in table else Fraction(0)
        return TaskConfig(task, activation, priority, period=ns(table, "period_ns", where), phase=phase, roles=roles)
    if activation == "trigger":
        prescaler = integer(table, "prescaler", where)
        if prescaler < 1:
            raise ConfigError(f"parameter {where}.prescaler must be at least 1: {prescaler}")
        return TaskConfig(task, activation, priority, trigger=text(table, "trigger", where), prescaler=prescaler,
                          roles=roles)
    if activation == "sporadic":
        return TaskConfig(task, activation, priority, min_gap=ns(table, "min_ns", where), roles=roles)
    raise ConfigError(f"parameter {where}.activation is not timer, trigger or sporadic: {activation!r}")
