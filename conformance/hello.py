"""The adapter's hello answer: what the runner needs from it, checked once for every kind of adapter."""

from __future__ import annotations

from .session import AdapterStartError

ORDERS = ("le", "be")


def check_hello(info, suite: str) -> dict:
    """``implementation`` (text), ``suites`` (must list ``suite``) and ``byte_orders`` (the orders it emits);
    raises AdapterStartError with what is wrong."""
    if not isinstance(info, dict):
        raise AdapterStartError(f"the adapter's hello answered a {type(info).__name__}, not an object")
    implementation, suites, orders = info.get("implementation"), info.get("suites"), info.get("byte_orders")
    if not isinstance(implementation, str) or not implementation.strip():
        raise AdapterStartError("the adapter's hello needs 'implementation': a non-empty string naming it")
    for key, value in (("suites", suites), ("byte_orders", orders)):
        if not isinstance(value, list) or not all(isinstance(x, str) for x in value):
            raise AdapterStartError(f"the adapter's hello needs '{key}': a list of strings (got {str(value)[:80]})")
    if not set(orders) <= set(ORDERS):
        raise AdapterStartError(f"the adapter's hello lists byte orders {orders[:4]}; orders are 'le' and 'be'")
    if suite not in suites:
        raise AdapterStartError(f"the adapter's hello does not list the suite {suite!r} (it lists {suites[:8]})")
    return {"implementation": implementation, "suites": suites, "byte_orders": orders}
