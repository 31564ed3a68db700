"""The limits on what one run reads: stated here, enforced by the loader and the parser, each a located
error when exceeded (E008; a number's length is E005). docs/guide/untrusted.md ("Limits") and
specs/diagnostics.md (E008) list them; a library user may pass tighter ones to ``verify.load``.

The defaults leave room for real models: a generated 10,000-task system (``benchmarks.generate``) is one
file of 2.7 MB and about 560,000 tokens.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Limits:
    file_bytes: int = 16 * 1024 * 1024  #: size of one file
    project_bytes: int = 64 * 1024 * 1024  #: total size of the files of one project
    files: int = 1000  #: files of one project, the root file included
    import_depth: int = 64  #: nesting of imports: the root file imports a file that imports a file ...
    tokens: int = 2_000_000  #: tokens (words, numbers, symbols; not white space or comments) of one file
    number_length: int = 40  #: characters of one number (E005)
    syntax_errors: int = 20  #: syntax errors reported for one file before it is given up

    def rows(self) -> list[tuple[str, str]]:
        """(what, limit) for documentation and ``--help``-style listings."""
        mib = 1024 * 1024
        return [("size of one file", f"{self.file_bytes // mib} MiB"),
                ("total size of the files of a project", f"{self.project_bytes // mib} MiB"),
                ("files of a project", f"{self.files:,}"),
                ("nesting of imports", f"{self.import_depth}"),
                ("tokens of one file", f"{self.tokens:,}"),
                ("characters of one number", f"{self.number_length}"),
                ("syntax errors reported for one file", f"{self.syntax_errors}")]


DEFAULT_LIMITS = Limits()

#: the largest message body the language server reads (bytes; ``verify lsp --max-message-bytes``): a
#: document at the size limit of one file (16 MiB) fits even with every character escaped in JSON as
#: ``\\uXXXX`` pairs. Kept here, apart from the server, so that the command line shows it without
#: importing the LSP libraries.
LSP_MESSAGE_BYTES = 128 * 1024 * 1024
#: the longest header line of a language server message (bytes)
LSP_HEADER_BYTES = 4096
