"""Text from outside, shown and written safely: the one place of the escaping rules (specs/diagnostics.md,
"Text from untrusted input").

Names, file names and lines of source text come from files verify did not write (a model, a CARET or
SmartMDSD file, a directory listing, the command line). Whatever they hold, what verify prints and what
it writes keeps its own structure:

- **printed** (``shown``): every character that is not printable — control characters such as ESC,
  BEL, CR, newline, tab and DEL, C1 controls, format characters such as the bidirectional overrides,
  line and paragraph separators, lone surrogates of an undecodable file name — is shown as its Python
  escape (``\\x1b``, ``\\n``, ``\\u202e``), so a value never moves the cursor, rings, recolours the
  terminal or starts a line of its own (a CI log's ``::error`` command). ``shown_lines`` does the same
  but keeps the newlines of a multi-line report; ``shown_columns`` escapes a line of a snippet and moves
  the columns of its underlined region with it.
- **written** into generated files: ``comment`` (a line comment's text: one line, escaped as printed),
  ``yaml_string`` (a YAML double-quoted scalar: no value is read as a boolean, null or number) and
  ``c_string`` (a C++ string literal's text).

JSON needs nothing here: ``json.dumps`` escapes every control character (and, as verify calls it, every
character beyond ASCII).
"""
from __future__ import annotations

#: the escapes of the characters Python spells short (``repr``'s), kept for readability
_SHORT = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


def escape(ch: str) -> str:
    """One character as its Python escape: ``\\n``, ``\\x1b``, ``\\u202e``, ``\\U000e0001``."""
    if ch in _SHORT:
        return _SHORT[ch]
    code = ord(ch)
    if code <= 0xFF:
        return f"\\x{code:02x}"
    return f"\\u{code:04x}" if code <= 0xFFFF else f"\\U{code:08x}"


def shown(text: str) -> str:
    """``text`` for one line of output: every character that is not printable escaped (a space stays)."""
    if text.isprintable():
        return text
    return "".join(ch if ch.isprintable() else escape(ch) for ch in text)


def shown_lines(text: str) -> str:
    """``text`` of several lines for output: as ``shown``, but its newlines (and tabs) kept."""
    if text.isprintable():
        return text
    return "\n".join("\t".join(shown(part) for part in line.split("\t")) for line in text.split("\n"))


def shown_columns(line: str, start: int, end: int) -> tuple[str, int, int]:
    """``line`` shown (``shown``) and the 1-based columns [``start``, ``end``) of a region of it moved to
    where the region is in the shown text (an escape is wider than its character)."""
    if line.isprintable():
        return line, start, end
    first = max(start, 1) - 1
    last = max(end - 1, first)
    before, region = shown(line[:first]), shown(line[first:last])
    beyond_start = max(0, first - len(line))  # (a region past the end of the line keeps its distance)
    beyond_end = max(0, last - max(first, len(line)))
    new_start = len(before) + 1 + beyond_start
    return before + region + shown(line[last:]), new_start, new_start + len(region) + beyond_end


def comment(text: str) -> str:
    """``text`` for a line comment of a generated file: one line whatever it holds (``shown``)."""
    return shown(text)


def yaml_string(text: str) -> str:
    """``text`` as a YAML double-quoted scalar: a string whatever it says (``yes``, ``null``, ``1e3``)."""
    body = text.replace("\\", "\\\\").replace('"', '\\"')
    return '"' + "".join(ch if ch.isprintable() else escape(ch) for ch in body) + '"'


def c_string(text: str) -> str:
    """``text`` as a C++ string literal (quotes included): backslashes, quotes and every character that
    is not printable ASCII escaped (an octal escape, which, unlike ``\\x``, ends after three digits)."""
    out = []
    for byte in text.encode("utf-8", "surrogatepass"):
        ch = chr(byte)
        if ch in '"\\?':  # (``?``: no trigraph)
            out.append("\\" + ch)
        elif 0x20 <= byte < 0x7F:
            out.append(ch)
        else:
            out.append(f"\\{byte:03o}")
    return '"' + "".join(out) + '"'
