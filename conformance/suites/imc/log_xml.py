"""The IMC.xml a log was written with: DUNE's Logging task puts ``IMC.xml.gz`` (the definitions it was built with)
beside ``Data.lsf``; Neptus writes ``IMC.xml``. Read bounded (a gzip one decompressed as logs are), made into the
definitions the log is judged by, its version shown, and compared with the suite's definitions message by message,
so that a report says how the two disagree."""

from __future__ import annotations

from pathlib import Path

from ...limits import XML_LIMIT
from .definitions import Definitions, MessageDef

NAMES = ("IMC.xml", "IMC.xml.gz", "IMC.xml.bz2")
LISTED = 8  # differences named in a report's note


def beside(path: Path, suite, use: bool):
    """(the suite over the log's own IMC.xml, where ``use`` and there is one that can be read, else None; notes;
    problems) for the log at ``path``."""
    if str(path) == "-":
        return None, ["read from standard input: no IMC.xml beside it, the suite's definitions judge it"], []
    found = next((path.parent / n for n in NAMES if (path.parent / n).is_file()), None)
    if found is None:
        return None, [f"no IMC.xml beside {path.name}: the suite's definitions ({suite.title}) judge it"], []
    try:
        own = suite.over_xml(_read(found))
    except ValueError as exc:
        return None, [], [f"{found}: {exc}; the suite's definitions ({suite.title}) judge the log"]
    version = own.editions[0][4:]
    said = f"definitions: {found.name} beside the log (IMC {version}, {len(own.defs.messages)} messages)"
    said += ", which judges it" if use else f", compared only: the definitions asked for ({suite.title}) judge it"
    return (own if use else None), [f"{said}; {agreement(own.defs, suite)}"], []


def _read(path: Path) -> bytes:
    """The XML's bytes (decompressed), at most XML_LIMIT; ValueError with one line."""
    from ...capture.streams import open_stream

    stream = open_stream(path)
    try:
        out, size = [], 0
        for piece in stream.pieces():
            size += len(piece)
            if size > XML_LIMIT:
                raise ValueError(f"over {XML_LIMIT >> 20} MB: not an IMC.xml")
            out.append(piece)
    finally:
        stream.handle.close()
    if stream.damage:
        raise ValueError(stream.damage[0].removeprefix(f"{path}: "))
    return b"".join(out)


def agreement(theirs: Definitions, suite) -> str:
    """How the log's definitions and the suite's agree on the messages both define (the suite's edition of the
    XML's version, else its first)."""
    wanted = theirs.editions[0]
    edition = wanted if wanted in suite.editions else suite.editions[0]
    ours = suite.defs
    shared = [m for m in ours.messages if m.id in theirs.by_id]
    found = [d for m in shared for d in differences(m, theirs.by_id[m.id], edition)]
    missing = [f"{m.abbrev} ({m.id}) is not in it" for m in ours.suite_messages if m.id not in theirs.by_id]
    against = f"against the suite's {suite.title}, edition {edition}" + (
        "" if edition == wanted else f" (it has no edition {wanted})")
    problems = missing + found
    if not problems:
        return f"{against}: it agrees on all {len(shared)} messages both define"
    listed = "; ".join(problems[:LISTED]) + (f"; and {len(problems) - LISTED} more" if len(problems) > LISTED else "")
    return f"{against}: they differ ({len(problems)}): {listed}"


def differences(ours: MessageDef, theirs: MessageDef, edition: str) -> list[str]:
    """What the wire carries differently for one message id: its name, its fields (name, type, order), the values
    of its enumerations and bitfields (in ``edition``)."""
    if ours.abbrev != theirs.abbrev:
        return [f"id {ours.id} is {theirs.abbrev} in the log's IMC.xml, {ours.abbrev} in the suite"]
    out = []
    mine = [(f.abbrev, f.type) for f in ours.fields]
    other = [(f.abbrev, f.type) for f in theirs.fields]
    if mine != other:
        at = next(i for i in range(max(len(mine), len(other))) if mine[i:i + 1] != other[i:i + 1])
        show = lambda fields: " ".join(f"{a}:{t}" for a, t in fields[at:at + 1]) or "nothing"  # noqa: E731
        out.append(f"{ours.abbrev} field {at + 1} is {show(other)} in the log's IMC.xml, {show(mine)} in the suite")
    by_name = {f.abbrev: f for f in theirs.fields}
    for f in ours.fields:
        other_field = by_name.get(f.abbrev)
        if other_field is None or not (f.enum_values or other_field.enum_values):
            continue
        a = {v.value: v.abbrev for v in f.enum_values if v.in_edition(edition)}
        b = {v.value: v.abbrev for v in other_field.enum_values}
        if a != b:
            only = sorted(set(b.items()) - set(a.items()))
            lacks = sorted(set(a.items()) - set(b.items()))
            out.append(f"{ours.abbrev}.{f.abbrev} values" + (f" {_values(only)} only in the log's IMC.xml" if only else "")
                       + ("," if only and lacks else "") + (f" {_values(lacks)} only in the suite" if lacks else ""))
    return out


def _values(items) -> str:
    return ", ".join(f"{value} {abbrev}" for value, abbrev in items)
