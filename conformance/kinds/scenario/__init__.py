"""The scenario case kind: behaviour over a live link, written as data and run by a sans-IO engine. Its names are
imported when first used (a run of byte vectors, or reading the vocabulary of live options, needs none of the
engine)."""

from importlib import import_module

_HOMES = {"Conductor": "conductor", "Outgoing": "conductor", "ScenarioKind": "kind", "Machine": "machine",
          "Program": "machine", "Addressing": "wire", "Composed": "wire", "Parsed": "wire", "Wire": "wire"}

__all__ = sorted(_HOMES)


def __getattr__(name: str):
    if name not in _HOMES:
        raise AttributeError(name)
    return getattr(import_module(f".{_HOMES[name]}", __name__), name)
