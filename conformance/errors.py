"""The errors a run ends on with one line and exit code 2, in a module of their own (light, so that every command
module raises the classes ``cli.main`` catches, also when the CLI runs as ``python -m``)."""


class UsageError(Exception):
    """A mistaken command line, or an input it names that cannot be used."""


class CorpusError(ValueError):
    """A case file or suite data file the runner cannot use; the message names the file and the JSON path."""
