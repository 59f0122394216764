"""The error of a mistaken command line: printed as one line, exit code 2. Its own module so that every
command module raises the class ``cli.main`` catches, also when the CLI runs as ``python -m``."""


class UsageError(Exception):
    pass
