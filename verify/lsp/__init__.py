"""The language server (``verify lsp``): ``features`` answers from the front end's results, ``server``
speaks LSP (pygls), ``transport`` reads its messages from standard input within bounds and answers
every bad request with an error response, ``synthchild`` runs synth for a code action in a process of
its own."""
