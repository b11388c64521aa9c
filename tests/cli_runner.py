"""The CLI run in process for the tests that read its exit code and streams
(imported by name: pytest puts this folder on ``sys.path``)."""

import warnings

import numpy as np


def in_process(capsys, *args):
    """``inskit ARGS`` through the entry point, in process: (exit code, stdout, stderr)."""
    from inskit.cli import main

    with warnings.catch_warnings(), np.errstate():  # main() silences both for the process: not beyond here
        try:
            main([str(a) for a in args])
            code = 0
        except SystemExit as exc:
            code = exc.code
    out = capsys.readouterr()
    return code, out.out, out.err
