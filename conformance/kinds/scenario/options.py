"""A run's settings for live cases (scenarios, robustness), checked against the suite's vocabulary (its
exchanges file: parameters, effects, services): one-line ValueErrors for anything unknown or malformed."""

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


def claims(behaviour: dict, doc) -> set[str]:
    """The services a claims document (``{"services": [...]}``) says the target implements."""
    if (not isinstance(doc, dict) or not isinstance(doc.get("services"), list) or set(doc) - {"services", "description"}
            or not all(isinstance(s, str) for s in doc["services"])):
        raise ValueError('expected {"services": [NAME, ...]} (optionally with "description")')
    unknown = [s for s in doc["services"] if s not in behaviour["services"]]
    if unknown:
        raise ValueError(f"unknown service {str(unknown[0])[:40]!r} (services: {', '.join(behaviour['services'])})")
    return set(doc["services"])
