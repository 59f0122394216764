"""Hangs when asked to decode the trigger frame."""

import time

from reference import serve

serve(lambda reply: time.sleep(3600))
