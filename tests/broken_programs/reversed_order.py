"""A correct program that answers out of order: each burst of requests in reverse."""

import json
import os
import select
import sys

from reference import answer

pending, buffer = [], b""
while True:
    if not select.select([0], [], [], 0.02)[0] or len(pending) >= 16:  # input idle or a burst collected
        sys.stdout.writelines(json.dumps(answer(request)) + "\n" for request in reversed(pending))
        sys.stdout.flush()
        pending.clear()
        continue
    chunk = os.read(0, 1 << 20)
    if not chunk:
        break
    *lines, buffer = (buffer + chunk).split(b"\n")
    pending += [json.loads(line) for line in lines]
