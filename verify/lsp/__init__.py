"""The language server (``verify lsp``): ``features`` answers from the front end's results, ``server``
speaks LSP (pygls) over standard input and output."""
