"""Decodes the trigger frame (a LblRange) with range + 1."""

import json

from reference import serve


def lie(reply):
    reply["message"]["fields"]["range"] += 1
    return json.dumps(reply)


serve(lie)
