"""The IMC suite: LSTS's Inter-Module Communication protocol, networking messages 150–188 and acoustic
messages 200–216 (seeds 000–003), as byte vectors in both byte orders."""


def load(folder=None):
    """The suite over its packaged data, or over a folder given instead (``suite.load``, imported when called)."""
    from .suite import load as load_suite

    return load_suite(folder)
