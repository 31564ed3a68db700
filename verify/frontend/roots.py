"""Where imports may lead: the project root and the library directories (specs/language.md §1.1).

A model's files are untrusted input (``prove`` runs on pull requests), so an import is confined before
any file is opened. It names a ``.vfy`` file by a relative path, looked up relative to the importing
file, then in each library directory in order. The file must lie inside an *allowed directory* — the
project root or a library directory — both as written (a ``..`` that climbs out is refused) and once
symbolic links are followed (a link that leads out is refused). An absolute path is refused. The file
given on the command line obeys the same rule, and so does the ``pyproject.toml`` (inside its own
directory): ``verify.core.fileaccess`` states it once for every file verify reads or writes.

The project root is the directory of the file given on the command line, unless ``--root DIR`` or the
``root`` of a ``[tool.verify]`` table in the nearest ``pyproject.toml`` says otherwise; library
directories come from ``--include DIR`` and that table's ``include``. A ``pyproject.toml`` belongs to the
project and is untrusted too: the directories it names must lie inside its own directory.
"""
from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field

from ..core.fileaccess import Area, Refused, inside, read_regular
from ..core.source import Span


@dataclass(frozen=True)
class Refusal:
    """Why an import is not followed: a diagnostic's code, message, label and help."""

    code: str
    message: str
    label: str
    help: str


@dataclass(frozen=True)
class Roots:
    """The allowed directories of one project: ``root`` first, then the library directories."""

    root: str
    include: tuple[str, ...] = ()
    #: how messages name the root (default: its path)
    label: str = field(default="", compare=False)
    #: the allowed directories, as written and once links are followed (``verify.core.fileaccess``)
    area: Area = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "area", Area((self.root, *self.include)))

    @classmethod
    def of_file(cls, path: str, root: str | None = None, include: tuple[str, ...] = ()) -> Roots:
        """The roots of a project whose root file is ``path``: ``root`` or the file's directory."""
        if root is not None:
            return cls(root, tuple(include))
        return cls(os.path.dirname(path) or os.curdir, tuple(include), f"the directory of `{path}`")

    def contains_as_written(self, path: str) -> bool:
        """``path`` lies inside an allowed directory, links not followed."""
        return self.area.holds_as_written(path)

    def contains(self, path: str) -> bool:
        """``path`` lies inside an allowed directory as written and once links are followed."""
        return self.area.holds(path)

    def describe(self) -> str:
        """The allowed directories for a message: "the project root `R`" (and "or the library ...")."""
        text = f"the project root ({self.label})" if self.label else f"the project root `{self.root}`"
        if self.include:
            text += " or the library director" + ("y " if len(self.include) == 1 else "ies ") + \
                    ", ".join(f"`{d}`" for d in self.include)
        return text

    def resolve(self, importer: str, target: str) -> str | Refusal:
        """The file that ``import "target"`` in file ``importer`` names, or why it is refused. The file is
        not opened; it need not exist (the loader then reports E004)."""
        from ..core.sanitize import shown as printable

        shown = printable(target)
        if "\0" in target:
            return Refusal("E004", f"invalid file name `{shown}`: it contains a NUL character", "cannot be read",
                           "correct the file name")
        if os.path.isabs(target):
            return Refusal("E006", f"import of an absolute path `{shown}`", "absolute path",
                           "name the file relative to the importing file; for a library elsewhere, run with "
                           "`--include DIR` and import it by its path inside DIR")
        local = os.path.normpath(os.path.join(os.path.dirname(importer), target))
        if not self.contains_as_written(local):
            return Refusal("E006", f"import `{shown}` leads outside {self.describe()}", "leads outside",
                           "keep imported files inside the project root, choose a larger root with `--root DIR`, "
                           "or name a library directory with `--include DIR`")
        if not target.endswith(".vfy"):
            return Refusal("E007", f"import `{shown}` does not name a .vfy file", "not a model file",
                           "an import names a model file whose name ends in `.vfy`")
        candidates = [local]
        for library in self.include:
            found = os.path.normpath(os.path.join(library, target))
            if inside(os.path.abspath(found), os.path.abspath(library)):
                candidates.append(found)
        chosen = next((c for c in candidates if os.path.lexists(c)), local)
        if not self.contains(chosen):
            return Refusal("E006", f"import `{shown}` is a symbolic link to a file outside {self.describe()}",
                           "leads outside", "copy the file into the project, or name the directory it lies in "
                           "with `--include DIR`")
        return chosen


#: the keys a ``[tool.verify]`` table may hold
SETTING_KEYS = ("root", "include")
MAX_PYPROJECT_BYTES = 1024 * 1024
#: why a ``pyproject.toml`` is not read, by ``fileaccess.Refused.reason`` (its content is never shown)
REFUSED_SETTINGS = {"outside": "is a symbolic link to a file outside its own directory",
                    "link": "is a symbolic link", "special": "is not a regular file (a pipe, device or socket)",
                    "directory": "is a directory", "missing": "does not exist", "name": "is not a valid file name"}


@dataclass(frozen=True)
class Settings:
    """What a ``[tool.verify]`` table says (paths as the loader uses them: the table's directory joined)."""

    path: str | None = None  # the pyproject.toml they come from
    root: str | None = None
    include: tuple[str, ...] = ()
    text: str = field(default="", repr=False)  # (for the snippet of a report)


@dataclass(frozen=True)
class SettingsError:
    span: Span
    message: str
    label: str
    help: str
    text: str = field(default="", repr=False)  # the file's text, for the snippet


def find_pyproject(start: str) -> str | None:
    """The nearest ``pyproject.toml`` in ``start`` or a directory above it, not above the repository
    (a directory holding ``.git``)."""
    here = os.path.abspath(start)
    while True:
        candidate = os.path.join(here, "pyproject.toml")
        if os.path.lexists(candidate) and not os.path.isdir(candidate):  # (a link or FIFO: found, then refused)
            return candidate
        if os.path.exists(os.path.join(here, ".git")):
            return None
        parent = os.path.dirname(here)
        if parent == here:
            return None
        here = parent


def read_settings(pyproject: str) -> Settings | SettingsError:
    """The ``[tool.verify]`` table of ``pyproject`` (empty settings when it has none)."""
    import tomllib

    start = Span(pyproject, 1, 1, 1, 1)
    try:
        raw = read_regular(pyproject, MAX_PYPROJECT_BYTES, Area((os.path.dirname(pyproject),)))
        text = raw.decode("utf-8")
    except Refused as refused:
        return SettingsError(start, f"{pyproject} {REFUSED_SETTINGS[refused.reason]}; it is not read", "not read",
                             "a pyproject.toml is a regular file in the directory it configures: replace the "
                             "link or special file with one, or remove it")
    except (OSError, UnicodeDecodeError) as err:
        return SettingsError(start, f"cannot read {pyproject}: {getattr(err, 'strerror', None) or err}",
                             "cannot be read", "fix the file, or remove it")
    if len(raw) > MAX_PYPROJECT_BYTES:
        return SettingsError(start, f"{pyproject} is larger than 1 MiB", "too large",
                             "a pyproject.toml is a small file: check that this is the right one")

    def fail(span: Span, message: str, label: str, help: str) -> SettingsError:
        return SettingsError(span, message, label, help, text)

    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        line, column = _toml_position(str(err))
        return fail(Span(pyproject, line, column, line, column + 1),
                    f"{pyproject} is not valid TOML: {str(err).split(' (at ')[0]}", "invalid TOML",
                    "fix the TOML syntax")
    tool = data.get("tool")
    table = tool.get("verify") if isinstance(tool, dict) else None
    if table is None:
        return Settings(pyproject)
    where = _key_span(pyproject, text)
    if not isinstance(table, dict):
        return fail(where("verify"), "`tool.verify` must be a table", "not a table",
                    'write `[tool.verify]` with `root = "DIR"` or `include = ["DIR", ...]` below it')
    from ..core.diagnostics import suggest

    for key in table:
        if key not in SETTING_KEYS:
            hint = suggest(key, SETTING_KEYS)
            return fail(where(key), f"unknown setting `{key}` in [tool.verify]", "unknown setting",
                        f"did you mean `{hint}`?" if hint else "known settings: " + ", ".join(SETTING_KEYS))
    root = table.get("root")
    include = table.get("include", [])
    if root is not None and not isinstance(root, str):
        return fail(where("root"), "`root` must be a string (a directory)", "not a string",
                    'write `root = "DIR"`, relative to this file')
    if not isinstance(include, list) or not all(isinstance(d, str) for d in include):
        return fail(where("include"), "`include` must be a list of strings (directories)", "not a list of strings",
                    'write `include = ["DIR", ...]`, relative to this file')
    base = os.path.dirname(pyproject)
    own = Area((base,))
    named = ([("root", root)] if root is not None else []) + [("include", d) for d in include]
    resolved = []
    for key, value in named:
        path = os.path.normpath(os.path.join(base, value))
        if "\0" in value or os.path.isabs(value) or not own.holds(path):
            return fail(where(key), f"`{key}` names `{value}`, which lies outside the directory of {pyproject}",
                        "leads outside", "a pyproject.toml may only name directories inside its own directory; "
                        "pass a directory elsewhere on the command line (`--root`, `--include`)")
        resolved.append(path)
    if root is not None:
        return Settings(pyproject, resolved[0], tuple(resolved[1:]), text)
    return Settings(pyproject, None, tuple(resolved), text)


def _toml_position(message: str) -> tuple[int, int]:
    import re

    m = re.search(r"at line (\d+), column (\d+)", message)
    return (int(m.group(1)), int(m.group(2))) if m else (1, 1)


def _key_span(path: str, text: str) -> Callable[[str], Span]:
    """A function giving the span of a key of the ``[tool.verify]`` table in ``text`` (the table's
    header when the key is not found on a line of its own)."""
    import re

    lines = text.split("\n")
    header = next((i for i, ln in enumerate(lines) if re.match(r"\s*\[\s*tool\s*\.\s*verify\s*\]", ln)), None)

    def where(key: str) -> Span:
        start = header + 1 if header is not None else 0
        for i in range(start, len(lines)):
            if header is not None and i > start and re.match(r"\s*\[", lines[i]):
                break
            m = re.match(rf"\s*({re.escape(key)})\s*=", lines[i])
            if m:
                return Span(path, i + 1, m.start(1) + 1, i + 1, m.end(1) + 1)
        line = (header or 0) + 1
        return Span(path, line, 1, line, len(lines[line - 1]) + 1 if lines else 2)

    return where


@dataclass(frozen=True)
class RootsProblem:
    """Why the roots of a project cannot be set: a diagnostic's parts, and the text of the file it points
    into (a ``pyproject.toml``; empty for the command line)."""

    code: str
    message: str
    span: Span
    label: str
    help: str
    text: str = field(default="", repr=False)


def project_roots(path: str, root: str | None = None, include: tuple[str, ...] = (), *,
                  config: bool = True) -> tuple[Roots | None, list[RootsProblem]]:
    """The allowed directories for the project whose root file is ``path``: ``root`` and ``include`` as
    given (the command line), completed from the nearest ``pyproject.toml`` when ``config``. Returns the
    roots, or None with the problems."""
    settings = Settings()
    if config:
        pyproject = find_pyproject(os.path.dirname(os.path.abspath(path)))
        if pyproject is not None:
            found = read_settings(pyproject)
            if isinstance(found, SettingsError):
                return None, [RootsProblem("E009", found.message, found.span, found.label, found.help, found.text)]
            settings = found
    chosen = root if root is not None else settings.root
    roots = Roots.of_file(path, chosen, tuple(include) + settings.include)
    problems = []
    for directory, given in [(roots.root, "--root" if root is not None else "root")] + \
                            [(d, "--include") for d in roots.include]:
        if not os.path.isdir(directory):
            where = Span(settings.path, 1, 1, 1, 1) if given == "root" and settings.path else \
                Span("<command line>", 1, 1, 1, 1)
            problems.append(RootsProblem("E004", f"{given} `{directory}` is not a directory", where, "not a directory",
                                         "name an existing directory", settings.text if given == "root" else ""))
    if problems:
        return None, problems
    if not roots.contains_as_written(path):
        where = Span("<command line>", 1, 1, 1, 1)
        origin = "`--root`" if root is not None else f"the `root` of {settings.path}"
        return None, [RootsProblem("E006", f"{path} lies outside the project root `{roots.root}` ({origin})", where,
                                   "outside the root", "run on a file inside the root, or choose the root with "
                                   "`--root DIR`")]
    if not roots.contains(path):
        # (the name on the command line is trusted, the file it names is the project's: a link committed in
        # its place may lead anywhere, and what it leads to is never read)
        return None, [RootsProblem("E006", f"{path} is a symbolic link to a file outside {roots.describe()}; it "
                                   "is not read", Span(path, 1, 1, 1, 1), "leads outside",
                                   "run on the model file itself, or choose a root that holds it with `--root DIR`")]
    return roots, []
