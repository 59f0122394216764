"""The adapter's hello answer: what the runner needs from it, checked once for every kind of adapter."""

from __future__ import annotations

from .session import AdapterStartError


def check_hello(info, suite: str, encodings_key: str, encodings: tuple[str, ...]) -> dict:
    """``implementation`` (text), ``suites`` (must list ``suite``), the encodings the implementation emits
    under ``encodings_key`` (e.g. ``byte_orders``), and optionally ``errata`` (the key of the implementation
    errata that apply to it) and ``kinds`` (the case kinds it runs: ``vector`` by default); raises AdapterStartError saying what is wrong."""
    if not isinstance(info, dict):
        raise AdapterStartError(f"the adapter's hello answered a {type(info).__name__}, not an object")
    implementation, suites, emits = info.get("implementation"), info.get("suites"), info.get(encodings_key)
    if not isinstance(implementation, str) or not implementation.strip():
        raise AdapterStartError("the adapter's hello needs 'implementation': a non-empty string naming it")
    for key, value in (("suites", suites), (encodings_key, emits)):
        if not isinstance(value, list) or not all(isinstance(x, str) for x in value):
            raise AdapterStartError(f"the adapter's hello needs '{key}': a list of strings (got {str(value)[:80]})")
    if not set(emits) <= set(encodings):
        raise AdapterStartError(f"the adapter's hello lists {encodings_key} {emits[:4]}; the suite {suite!r} has "
                                f"{', '.join(encodings)}")
    if suite not in suites:
        raise AdapterStartError(f"the adapter's hello does not list the suite {suite!r} (it lists {suites[:8]})")
    errata = info.get("errata")
    if errata is not None and not isinstance(errata, str):
        raise AdapterStartError("the adapter's hello gives 'errata' as something other than a string")
    kinds = info.get("kinds", ["vector"])
    if not isinstance(kinds, list) or not kinds or not all(isinstance(k, str) for k in kinds):
        raise AdapterStartError(f"the adapter's hello gives 'kinds' as something other than a list of case kinds "
                                f"(got {str(kinds)[:80]})")
    return {"implementation": implementation, "suites": suites, "emits": emits, "errata": errata, "kinds": kinds}
