"""A run's settings for live cases (scenarios, robustness), checked against the suite's vocabulary (its
exchanges file: parameters, effects, services and capabilities): one-line ValueErrors for anything unknown or
malformed."""

from __future__ import annotations


def parameters(behaviour: dict, items: list[str]) -> dict:
    """``NAME=VALUE`` items as the run's parameters, typed."""
    known, out = behaviour["params"], {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or name not in known:
            raise ValueError(f"--param {item!r}: expected NAME=VALUE with NAME one of {', '.join(known) or 'none'}")
        if known[name]["type"] == "integer":
            try:
                out[name] = int(value, 0)
            except ValueError:
                raise ValueError(f"--param {item!r}: {name} is an integer (e.g. {known[name]['example']})") from None
        else:
            out[name] = value
    return out


def effects(behaviour: dict, text: str | None) -> set[str]:
    """The effects ``--allow-effects`` allows: none by default, ``all``, or a comma-separated list."""
    if text is None:
        return set()
    names = {n.strip() for n in text.split(",") if n.strip()}
    unknown = names - set(behaviour["effects"]) - {"all"}
    if unknown or not names:
        raise ValueError(f"--allow-effects {text!r}: expected all or a comma-separated list of "
                         f"{', '.join(behaviour['effects'])}")
    return names


SCOPES = ("any", "self", "none")  # a capability served to every system, only to the node's own, or not at all


def claims(behaviour: dict, doc) -> dict[str, str]:
    """What a claims document says the target serves, as capability -> "any" or "self" (whom it serves): its
    ``services`` claim each of their capabilities for any system, its ``capabilities`` (name -> "any", "self" or
    "none") claim one each, overriding its service's."""
    if (not isinstance(doc, dict) or set(doc) - {"services", "capabilities", "description"}
            or not {"services", "capabilities"} & set(doc)
            or not isinstance(doc.get("services", []), list) or not all(isinstance(s, str) for s in doc.get("services", []))
            or not isinstance(doc.get("capabilities", {}), dict)):
        raise ValueError('expected {"services": [NAME, ...], "capabilities": {NAME: "any"|"self"|"none", ...}} '
                         '(either or both; optionally with "description")')
    known = behaviour["capabilities"]
    unknown = [s for s in doc.get("services", []) if s not in behaviour["services"]]
    if unknown:
        raise ValueError(f"unknown service {str(unknown[0])[:40]!r} (services: {', '.join(behaviour['services'])})")
    out = {name: "any" for name, c in known.items() if c["service"] in doc.get("services", [])}
    for name, scope in doc.get("capabilities", {}).items():
        if name not in known:
            raise ValueError(f"unknown capability {str(name)[:40]!r} (capabilities: {', '.join(known)})")
        if scope not in SCOPES:
            raise ValueError(f"capability {name!r}: {str(scope)[:20]!r} is not one of {', '.join(SCOPES)}")
        out[name] = scope
    return {name: scope for name, scope in out.items() if scope != "none"}
