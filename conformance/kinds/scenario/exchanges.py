"""Reading a suite's exchange rules (exchanges.json): which exchange a request opens, and the values a rule
names, resolved through the suite's wire."""

from __future__ import annotations


def resolved(wire, message: str, path: str, names, edition: str) -> list:
    """What the wire carries for each of ``names`` of field ``path`` (names the edition lacks left out)."""
    out = []
    for name in names:
        try:
            out.append(wire.resolve(message, path, name, edition))
        except KeyError:
            continue
    return out


def selected(wire, message: str, fields: dict, when: dict, edition: str) -> bool:
    """Whether ``fields`` hold one of the values ``when`` names for each of its fields."""
    return all(fields.get(f) in resolved(wire, message, f, names, edition) for f, names in when.items())


def exchange_for(exchanges, wire, message: dict, edition: str) -> dict | None:
    """The exchange a message (decoded form, values resolved) opens as a request, if any."""
    for ex in exchanges:
        request = ex["request"]
        if request["message"] == message["abbrev"] and selected(wire, message["abbrev"], message["fields"],
                                                                 request.get("when", {}), edition):
            return ex
    return None
