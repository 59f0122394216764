"""Dies (exit code 3) when asked to decode the trigger frame, after a word on stderr."""

import os
import sys

from reference import serve


def crash(reply):
    sys.stderr.write("crash.py: dying on the trigger frame\n")
    sys.stderr.flush()
    os._exit(3)


serve(crash)
