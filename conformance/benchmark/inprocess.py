"""In-process rows: the runner's own cost, imcpy and rosbags through it beside their bare calls, the renderers."""

from __future__ import annotations

import statistics
import time

from ..core.cases import expectation
from ..core.runner import run_cases
from ..files import open_corpus
from .measure import COUNTS, EDITION, ROS_EDITION, median_of


class TableAdapter:
    """A zero-cost implementation: answers looked up in tables made beforehand with the reference codec."""

    def __init__(self, suite, cases):
        from ..adapter_api import Rejected
        from ..suites.imc import codec

        self.rejected = Rejected
        self.decoded, self.encoded = {}, {}
        emits = frozenset({"le", "be"})
        for case in cases:
            for request in suite.kinds["vector"].plan(case.data, EDITION, emits):
                if request.frame is not None:
                    self.decoded[request.frame] = _outcome(lambda: codec.decode(suite.defs, request.frame))
                if request.message is not None:
                    self.encoded[(id(request.message), request.encoding)] = _outcome(
                        lambda: codec.encode(suite.defs, request.message, request.encoding))

    def hello(self) -> dict:
        return {"implementation": "a table of the reference codec's answers", "suites": ["imc"],
                "byte_orders": ["le", "be"]}

    def decode(self, suite: str, frame: bytes):
        return self._answer(self.decoded.get(frame))

    def encode(self, suite: str, message: dict, byte_order: str):
        return self._answer(self.encoded.get((id(message), byte_order)))

    def _answer(self, outcome):
        if outcome is None or isinstance(outcome, ValueError):
            raise self.rejected(str(outcome), getattr(outcome, "rule", None))
        return outcome


def _outcome(fn):
    try:
        return fn()
    except ValueError as exc:
        return exc


def imcpy_alone(suite, cases, emits: frozenset) -> float:
    """Seconds for the bare imcpy calls the corpus needs (decode via Packet.deserialize, encode via serialize)."""
    import imcpy

    frames, encodable = [], []
    for case in cases:
        for request in suite.kinds[case.kind].plan(case.data, EDITION, emits):
            if request.op in ("decode", "roundtrip"):
                frames.append(request.frame)
            if request.op in ("encode", "roundtrip") and case.data["expect"] == "valid":
                encodable.append(bytes.fromhex(case.data["frames"]["le"]))
    messages = [imcpy.Packet.deserialize(f) for f in encodable]
    start = time.perf_counter()
    for frame in frames:
        try:
            imcpy.Packet.deserialize(frame)
        except RuntimeError:
            pass
    for message in messages:
        message.serialize()
    return time.perf_counter() - start


def library_rows(suite, cases, repeat: int) -> dict[str, float]:
    import gc

    from ..adapters.imcpy_adapter import adapter
    from ..render import RENDERERS
    from ..sessions.library import LibrarySession

    table, imcpy = TableAdapter(suite, cases), adapter()
    gc.freeze()  # as the command line does once the corpus is loaded

    def run(implementation, name):
        return run_cases(LibrarySession(implementation, name), suite, cases, edition=EDITION, adapter=name)
    run(table, "table")
    result = run(imcpy, "imcpy")
    out = {"zero": median_of(repeat, lambda: run(table, "table")),
           "library": median_of(repeat, lambda: run(imcpy, "imcpy")),
           "imcpy alone": statistics.median(imcpy_alone(suite, cases, frozenset({"le"})) for _ in range(repeat))}
    out["imcpy ratio"] = out["library"] / out["imcpy alone"]
    COUNTS["zero"] = COUNTS["library"] = len(cases)
    for fmt, render in RENDERERS.items():
        render(result)
        out[f"render {fmt}"] = median_of(repeat, lambda: render(result)) / len(result.cases)
    n = len(cases)
    print(f"IMC corpus in-process: {n} cases ({EDITION}): zero-cost adapter {out['zero']:.3f} s "
          f"({n / out['zero']:,.0f} cases/s); imcpy {out['library']:.3f} s ({n / out['library']:,.0f} cases/s); "
          f"imcpy's bare calls {out['imcpy alone']:.3f} s (the runner with imcpy: {out['imcpy ratio']:.2f}x)")
    print("reports, per case: " + ", ".join(f"{fmt} {out[f'render {fmt}'] * 1e6:.1f} µs" for fmt in RENDERERS))
    return out


def rosbags_alone(adapter, suite, cases) -> float:
    """Seconds for the bare rosbags calls the ROS corpus needs: deserialize every frame it decodes, serialize
    again what deserialized (no adapter conversion, no judging)."""
    work = []
    for case in cases:
        for request in suite.kinds[case.kind].plan(case.data, ROS_EDITION, frozenset({"ros1"})):
            if request.op == "decode":
                work.append((request.frame, adapter._typename(case.data["type"])))
    start = time.perf_counter()
    store = adapter.store
    for frame, typename in work:
        try:
            store.serialize_ros1(store.deserialize_ros1(frame, typename), typename)
        except Exception:  # a rejected frame costs what it costs
            pass
    return time.perf_counter() - start


def ros_rows(repeat: int) -> dict[str, float]:
    from ..adapters.genpy_adapter import GenpyAdapter
    from ..adapters.rosbags_adapter import RosbagsAdapter
    from ..sessions.library import LibrarySession

    suite, cases = open_corpus("ros_acomms")
    cases = [c for c in cases if c.kind == "vector" and expectation(c.data, ROS_EDITION) is not None]
    adapters = {"rosbags": RosbagsAdapter(), "genpy": GenpyAdapter()}
    out = {}
    for name, adapter in adapters.items():
        session = LibrarySession(adapter, name)
        out[f"ros {name}"] = median_of(repeat, lambda: run_cases(session, suite, cases, edition=ROS_EDITION,
                                                                 adapter=name))
    out["rosbags alone"] = statistics.median(rosbags_alone(adapters["rosbags"], suite, cases) for _ in range(repeat))
    out["rosbags ratio"] = out["ros rosbags"] / out["rosbags alone"]
    print(f"ros_acomms corpus in-process: {len(cases)} cases ({ROS_EDITION}): rosbags {out['ros rosbags']:.3f} s, "
          f"genpy {out['ros genpy']:.3f} s, rosbags' bare calls {out['rosbags alone']:.3f} s "
          f"(the runner with rosbags: {out['rosbags ratio']:.1f}x)")
    return out
