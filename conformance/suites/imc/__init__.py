"""The IMC suite: LSTS's Inter-Module Communication protocol, networking messages 150–188 and acoustic
messages 200–216 (seeds 000–003), as byte vectors in both byte orders; and the whole protocol (``imc-full``)."""

VARIANTS = {"imc-full": "every message of the IMC.xml imcpy ships (the seeds' corpus for theirs, generated for "
                        "the rest)"}


def load(folder=None):
    """The suite over its packaged data, or over a folder given instead (``suite.load``, imported when called)."""
    from .suite import load as load_suite

    return load_suite(folder)


def load_variant(name: str, folder=None):
    """``imc-full``: the suite over the whole-protocol folder of imcpy's IMC.xml, built into the cache the first
    time (``whole.whole_folder``); a folder given instead replaces it as for the suite itself. CorpusError when the
    folder cannot be built (no IMC.xml to fetch, an unwritable cache)."""
    from ...errors import CorpusError
    from .suite import load as load_suite, load_whole
    from .whole import whole_folder

    if folder is not None:
        return load_suite(folder)
    try:
        return load_whole(whole_folder())
    except (OSError, RuntimeError, ValueError) as exc:
        raise CorpusError(f"{name}: cannot build the whole protocol's corpus: {exc}") from None
