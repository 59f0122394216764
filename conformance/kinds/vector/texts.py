"""Text a reader decoded lossily: the one policy for the ``lossy`` outcome of every suite.

A text field holding bytes its type does not define (IMC plaintext beyond ASCII, a ROS string that is not UTF-8) may
come back with each run of bytes the reader could not read replaced by U+FFFD or '?' (one for each byte or one for
several, as decoders differ), every ASCII byte kept in its place and every character it did read (valid UTF-8) as it
was. Anything else (a byte dropped, a character invented, a Latin-1 reading) is not lossy but wrong.
"""

from __future__ import annotations

REPLACEMENTS = ("\ufffd", "?")
MAX_BYTES = 4096  # beyond this, only the exact bytes (the search is quadratic in the worst case)
MAX_SEQUENCE = 4  # the most bytes one replacement character stands for (a UTF-8 sequence)


def lossy_bytes(raw: bytes, answered: bytes) -> bool:
    """Whether ``answered`` (the bytes an answer stands for, whatever its form: a string's UTF-8, ``{"hex"}``'s bytes)
    is ``raw`` read lossily: one verdict for one reading, however the adapter wrote it."""
    try:
        text = answered.decode("utf-8")
    except UnicodeDecodeError:  # a lossy reader's text is text: bytes that are not UTF-8 are another reading
        return False
    return lossy_match(raw, text)


def lossy_match(raw: bytes, text: str) -> bool:
    """Whether ``text`` is ``raw`` read as described above (iterative: no recursion the input can drive)."""
    if len(raw) > MAX_BYTES or len(text) > MAX_BYTES:
        return False
    reached = {(0, 0)}
    frontier = [(0, 0)]
    while frontier:
        i, j = frontier.pop()
        if i == len(raw) and j == len(text):
            return True
        if i == len(raw) or j == len(text):
            continue
        for step in _steps(raw, i, text[j]):
            state = (i + step, j + 1)
            if state not in reached:
                reached.add(state)
                frontier.append(state)
    return False


def _steps(raw: bytes, i: int, char: str):
    """How many bytes of ``raw`` from ``i`` the character ``char`` can stand for."""
    if raw[i] < 0x80:
        if char == chr(raw[i]):
            yield 1
        return
    encoded = char.encode("utf-8", "surrogatepass")
    if ord(char) >= 0x80 and char != "\ufffd" and raw.startswith(encoded, i):
        yield len(encoded)
    if char in REPLACEMENTS:
        k = 0
        while k < MAX_SEQUENCE and i + k < len(raw) and raw[i + k] >= 0x80:
            k += 1
            yield k
