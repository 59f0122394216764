"""What a result the command line writes records of how it was made (``core.results.Provenance``)."""

from __future__ import annotations

from pathlib import Path

from ..core.results import Provenance
from ..errors import CorpusError


def provenance(args, suite, selection: dict, *, errata: str | None = None, waivers: dict | None = None) -> Provenance:
    """The provenance of a command's result: this tool, the digest of the corpus ``args.vectors`` (or the suite's
    own) names, ``selection``, ``errata`` and ``waivers`` in effect, and the command line (``cli.main`` keeps it)."""
    from .. import __version__
    from ..files import corpus_digest

    directory = getattr(args, "vectors", None)
    try:
        corpus = corpus_digest(suite, Path(directory) if directory is not None else None)
    except ValueError as exc:  # a file of the corpus that cannot be read again
        raise CorpusError(str(exc)) from None
    return Provenance(f"imc-conformance {__version__}", corpus, selection, errata, waivers,
                      list(getattr(args, "command_line", ())))
