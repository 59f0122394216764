"""Sans-IO planning and judging of byte vectors, generic over a suite's codec.

A vector case holds frames (hex, by encoding) and/or a message in the suite's decoded form, and says
what a conforming implementation does with them: ``valid`` (encode to exactly the frame, decode to
exactly the message, re-encode its own decoding to the same bytes, describe the type as given),
``invalid`` (refuse, naming ``rule`` or another of its ``flaws`` if it can) or ``acceptable`` (one of
``outcomes``, each of which may give its own frames or decoded message, or tolerate a difference of its own:
``lossy`` text, a ``restamp``ed timestamp, as the suite's codec says). ``plan`` lists
the requests a case needs for an implementation that emits some encodings; ``judge`` turns each answer
into a check verdict, keeping both frames and the differing bytes (named by field) of a failure.

Each case is compiled once per edition (``_Compiled``: its expectation, its frames as bytes, its requests by
the encodings an implementation emits, and the canonical bytes of its decoded message), so that a run spends
its time on the implementation, not on re-reading the corpus's hex: a decoded answer whose canonical JSON is the
expected one's is a PASS at once (``orjson`` writes ``-0.0``, ``1.0`` and ``true`` apart from ``0.0``, ``1`` and
``1``, and refuses subclasses of its types here, so equal bytes mean equal values of equal types; as it writes a
NaN or an infinity as ``null``, the shortcut is not taken for a message holding a null); any other answer goes
through the suite's comparison policy.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import orjson

from ...core.cases import expectation
from ...core.evidence import ANY
from ...core.results import ByteDiff, CheckResult
from ...core.session import Answer, Request
from ...core.verdicts import Verdict

FAILURE_KINDS = {"crash": Verdict.CRASH, "timeout": Verdict.TIMEOUT, "adapter-error": Verdict.ADAPTER_ERROR,
                 "unsupported": Verdict.UNSUPPORTED}


@dataclass(frozen=True)
class Span:
    """Bytes ``[start, end)`` of a frame hold ``path`` (e.g. ``LblRange.range``), of wire type ``type``.

    ``role`` tells a value from what the wire adds: e.g. ``length``, ``count``, ``id``, ``header``, ``footer``.
    """

    start: int
    end: int
    path: str
    type: str
    role: str = "value"


class VectorCodec(Protocol):
    """What a suite gives the vector kind: its reference codec and decoded-form policy."""

    encodings: tuple[str, ...]
    rules: frozenset[str]  # the rule names a refusal may give

    def encode(self, message: dict, encoding: str, edition: str) -> bytes:
        """The reference encoding; raises ValueError if the message cannot be encoded."""

    def layout(self, frame: bytes, encoding: str, case: dict, edition: str) -> list[Span]:
        """The byte map of a frame of this case; raises ValueError if the frame cannot be laid out."""

    def differences(self, expected: dict, actual, nan_payload: bool, edition: str) -> list:
        """How a decoded message differs from the expected one (each difference printable)."""

    def malformed(self, message, case: dict, edition: str) -> str | None:
        """Why an answered message is not a well-formed decoded form (the adapter's fault), or None."""

    def params(self, case: dict, op: str, encoding: str | None) -> dict:
        """The operation's further parameters as the adapter protocol names them."""

    def describe_differences(self, expected: dict, actual, case: dict, edition: str) -> list[str]:
        """How an answered description of a type differs from the expected one."""

    def decode(self, frame: bytes, encoding: str, case: dict, edition: str) -> dict:
        """The reference decoding of a frame an implementation wrote; raises ValueError if it refuses it."""

    def tolerates(self, outcome: str, op: str, difference) -> bool:
        """Whether an outcome (``lossy``, ``restamp``, ...) permits this difference from the case's message in an
        answer to ``op`` (decode, encode, roundtrip)."""


VALID_PASS = {"decode": "decoded as expected", "encode": "frame matches", "roundtrip": "re-encoded to the same frame"}


@dataclass
class _Compiled:
    """A case as a run needs it, worked out once per edition."""

    case: dict  # kept: the cache is keyed by its identity
    expect: str | None
    frames: dict[str, bytes]
    canonical: bytes | None  # orjson bytes of the expected decoded message (None: no shortcut for this case)
    plans: dict[frozenset, list[Request]] = field(default_factory=dict)  # by the encodings emitted


class VectorKind:
    """Plans and judges the byte vectors of one suite."""

    name = "vector"

    def __init__(self, codec: VectorCodec):
        self.codec = codec
        self._compiled: dict[tuple[int, str], _Compiled] = {}
        self._passes: dict[str, CheckResult] = {}  # the PASS of each check name, shared (never changed)

    def compiled(self, case: dict, edition: str) -> _Compiled:
        key = (id(case), edition)
        found = self._compiled.get(key)
        if found is None:
            message = case.get("message")
            found = self._compiled[key] = _Compiled(
                case, expectation(case, edition), {e: bytes.fromhex(h) for e, h in case.get("frames", {}).items()},
                _canonical(message))
        return found

    def forget(self, case: dict, edition: str) -> None:
        """Drop what was compiled for ``case`` (a generated case judged once: the cache must not grow with them)."""
        self._compiled.pop((id(case), edition), None)

    # ------------------------------------------------------------ planning

    def plan(self, case: dict, edition: str, emits: set[str], options: dict | None = None) -> list[Request]:
        """The requests to make for ``case``; encoding in an encoding the implementation does not emit is not
        applicable. (The list is the compiled case's: a caller must not change it.)"""
        compiled = self.compiled(case, edition)
        key = emits if isinstance(emits, frozenset) else frozenset(emits)
        plan = compiled.plans.get(key)
        if plan is None:
            plan = compiled.plans[key] = self._plan(case, compiled, emits)
        return plan

    def _plan(self, case: dict, compiled: _Compiled, emits: set[str]) -> list[Request]:
        if compiled.expect is None:
            return []
        frames, out = compiled.frames, []
        for check in case["checks"]:
            if check == "roundtrip":
                out += [self._request(case, compiled, f"roundtrip-{e}", "roundtrip", e)
                        for e in self.codec.encodings if e in emits and e in frames]
            elif check == "describe":
                out.append(Request("describe", "describe", params=self.codec.params(case, "describe", None),
                                   context=compiled))
            else:
                op, encoding = check.split("-", 1)
                if op != "encode" or encoding in emits:
                    out.append(self._request(case, compiled, check, op, encoding))
        return out

    def _request(self, case: dict, compiled: _Compiled, check: str, op: str, encoding: str) -> Request:
        params = self.codec.params(case, op, encoding)
        if op == "encode":
            return Request(check, op, encoding, message=case["message"], params=params, context=compiled)
        return Request(check, op, encoding, frame=compiled.frames[encoding], params=params, context=compiled)

    # ------------------------------------------------------------ judging

    def judge(self, case: dict, edition: str, request: Request, answer: Answer) -> CheckResult:
        compiled = request.context if request.context is not None else self.compiled(case, edition)
        if answer.kind == "ok" and compiled.expect == "valid" and not answer.note:  # the common case, at once
            op = request.op
            if op == "decode":
                if compiled.canonical is not None and _canonical(answer.message) == compiled.canonical:
                    return self._pass(request.check, op)
            elif op != "describe" and answer.frame == compiled.frames.get(request.encoding):
                return self._pass(request.check, op)
        result = self._judge(case, compiled, edition, request, answer)
        if answer.note:
            result.note = answer.note
        return result

    def _pass(self, check: str, op: str) -> CheckResult:
        """The PASS of a valid case's check, shared (its name says its operation, and so its detail)."""
        found = self._passes.get(check)
        if found is None:
            found = self._passes[check] = CheckResult(check, Verdict.PASS, VALID_PASS[op])
        return found

    def _judge(self, case: dict, compiled: _Compiled, edition: str, request: Request, answer: Answer) -> CheckResult:
        if answer.kind in FAILURE_KINDS:
            return CheckResult(request.check, FAILURE_KINDS[answer.kind], answer.reason)
        if answer.kind == "rejected" and answer.rule is not None and answer.rule not in self.codec.rules:
            return CheckResult(request.check, Verdict.ADAPTER_ERROR, f"the refusal names the rule {answer.rule[:80]!r}, "
                               f"which the suite's rules do not have: {answer.reason}")
        if request.op == "describe":
            return self._describe(case, edition, request, answer)
        if compiled.expect == "valid":
            return self._valid(case, compiled, edition, request, answer)
        if compiled.expect == "invalid":
            return self._invalid(case, edition, request, answer)
        return self._acceptable(case, compiled, edition, request, answer)

    def _describe(self, case, edition, request, answer) -> CheckResult:
        if answer.kind == "rejected":
            return CheckResult(request.check, Verdict.FAIL, f"refused to describe the type: {answer.reason}")
        diffs = self.codec.describe_differences(case["describe"], answer.message, case, edition)
        if diffs and not isinstance(answer.message, dict):
            return CheckResult(request.check, Verdict.ADAPTER_ERROR, "malformed answer: no description object")
        if diffs:
            return CheckResult(request.check, Verdict.FAIL, "; ".join(diffs[:3]))
        return CheckResult(request.check, Verdict.PASS, "described as expected")

    def _decoded_wrongly(self, case, compiled, edition, request, answer, detail_prefix: str) -> CheckResult | None:
        """None if the decoded message is the expected one; else an ADAPTER_ERROR (malformed answer) or FAIL."""
        diffs = self.codec.differences(case["message"], answer.message,
                                       case.get("compare", {}).get("nan_payload", False), edition)
        if not diffs:
            return None
        malformed = self.codec.malformed(answer.message, case, edition)
        if malformed:
            return CheckResult(request.check, Verdict.ADAPTER_ERROR, malformed)
        expected = compiled.frames[request.encoding]
        return self.failure(case, edition, request, detail_prefix + "; ".join(str(d) for d in diffs[:5]), expected,
                            self.reencoded(answer.message, request.encoding, edition))

    def _valid(self, case, compiled, edition, request, answer) -> CheckResult:
        check = request.check
        if answer.kind == "rejected":
            return CheckResult(check, Verdict.FAIL, f"refused a valid {request.op}: {answer.reason}")
        if request.op == "decode":
            return (self._decoded_wrongly(case, compiled, edition, request, answer, "")
                    or CheckResult(check, Verdict.PASS, VALID_PASS["decode"]))
        expected = compiled.frames[request.encoding]
        if answer.frame != expected:
            return self.failure(case, edition, request, "", expected, answer.frame, locate=True)
        return CheckResult(check, Verdict.PASS, VALID_PASS[request.op])

    def _invalid(self, case, edition, request, answer) -> CheckResult:
        check, rule = request.check, case["rule"]
        if answer.kind == "ok" and request.op == "decode" and request.frame is not None:
            return self.accepted(case, edition, request, answer, f"accepted an invalid frame (rule {rule})")
        if answer.kind == "ok":
            return CheckResult(check, Verdict.FAIL, f"encoded a message it must refuse (rule {rule})")
        broken = (*case.get("flaws", {}).get("rules", (rule,)), *(() if "practice" not in case else (case["practice"],)))
        if answer.rule is not None and answer.rule not in broken:
            named = " or ".join(repr(r) for r in broken)
            return CheckResult(check, Verdict.NON_STRICT, f"rejected, but named rule {answer.rule!r} instead of {named}: {answer.reason}")
        return CheckResult(check, Verdict.PASS, f"rejected: {answer.reason}")

    def _acceptable(self, case, compiled, edition, request, answer) -> CheckResult:
        check = request.check
        permitted = {o["outcome"]: o for o in case["outcomes"]}
        if answer.kind == "rejected":
            if "reject" in permitted and answer.rule is not None and answer.rule not in permitted["reject"].get("rules", ()):
                return CheckResult(check, Verdict.NON_STRICT, f"rejected naming rule {answer.rule!r}, which this case "
                                   f"does not break: {answer.reason}", "reject")
            if "reject" in permitted:
                return CheckResult(check, Verdict.IMPL_DEFINED, f"rejected: {answer.reason}", "reject")
            return CheckResult(check, Verdict.FAIL, f"rejected, which this case does not permit: {answer.reason}")
        nan_payload = case.get("compare", {}).get("nan_payload", False)
        if request.op == "decode":
            for name, outcome in permitted.items():  # an outcome may decode to a message of its own
                if (name == "accept" or "message" in outcome) and not self.codec.differences(
                        outcome.get("message", case["message"]), answer.message, nan_payload, edition):
                    return CheckResult(check, Verdict.IMPL_DEFINED, "accepted" if name == "accept" else name, name)
            tolerated = self._tolerated(case, permitted, request.op, answer.message, nan_payload, edition)
            if tolerated:
                return CheckResult(check, Verdict.IMPL_DEFINED, tolerated[1], tolerated[0])
            return self._decoded_wrongly(case, compiled, edition, request, answer, "accepted, but decoded wrongly: ") or \
                CheckResult(check, Verdict.FAIL, "accepted, which this case does not permit")
        frames = {name: o.get("frames", case.get("frames")) for name, o in permitted.items() if name != "reject"}
        for name, candidate in frames.items():
            if candidate and candidate.get(request.encoding) == (answer.frame or b"").hex():
                return CheckResult(check, Verdict.IMPL_DEFINED, f"{name}: {answer.frame.hex()[:64]}", name)
        if answer.frame is not None:
            try:
                decoded = self.codec.decode(answer.frame, request.encoding, case, edition)
            except ValueError:
                decoded = None
            tolerated = decoded is not None and self._tolerated(case, permitted, request.op, decoded, nan_payload, edition)
            if tolerated:
                return CheckResult(check, Verdict.IMPL_DEFINED, tolerated[1], tolerated[0])
        reference = bytes.fromhex((frames.get("accept") or next(iter(frames.values()), {}))[request.encoding])
        return self.failure(case, edition, request, "encoded to a frame no outcome permits: ", reference, answer.frame,
                            locate=True)

    def _tolerated(self, case, permitted: dict, op: str, message, nan_payload: bool,
                   edition: str) -> tuple[str, str] | None:
        """(outcome, detail) if the message differs from the case's only where permitted outcomes (``lossy``,
        ``restamp``: those without frames or a message of their own) tolerate it, each difference by one; else None."""
        tolerant = [name for name, o in permitted.items() if name not in ("accept", "reject") and "frames" not in o
                    and "message" not in o]
        if not tolerant:
            return None
        diffs = self.codec.differences(case["message"], message, nan_payload, edition)
        used = []
        for diff in diffs:
            name = next((n for n in tolerant if self.codec.tolerates(n, op, diff)), None)
            if name is None:
                return None
            used.append((name, diff))
        if not used:
            return None
        detail = "; ".join(f"{n}: {d.path} {d.actual!r}"[:120] for n, d in used[:3])
        return "+".join(sorted({n for n, _ in used})), detail

    # ------------------------------------------------------------ evidence

    def evidence(self, case: dict, edition: str, request: Request, answer: Answer) -> tuple[str, str] | None:
        """What an answer shows of the implementation (core.evidence): a valid case answered shows that it reads
        (``decode-<encoding>``, a roundtrip too) or encodes (``encode-<encoding>``) the case's group in that encoding;
        a refusal of an invalid or acceptable case counts only from an implementation that does; a refusal of a valid
        one only from an implementation that does anything of the group (``ANY``: else it does not implement it)."""
        kind = answer.kind
        if (kind != "ok" and kind != "rejected") or request.op == "describe":
            return None
        compiled = request.context if request.context is not None else self.compiled(case, edition)
        capability = self.capability(case, request)
        if kind == "ok":
            return ("shows", capability) if compiled.expect == "valid" else None
        return "needs", ANY if compiled.expect == "valid" else capability

    def differences_in(self, case: dict, edition: str, check: CheckResult) -> list[tuple[str, object, object]]:
        """What a failed check of a valid case got wrong, value by value: (path, expected, answered), as the reference
        codec reads the frame the implementation wrote (or the message it read, re-encoded); [] where that cannot be
        read (a refusal, a frame the reference refuses)."""
        if check.actual is None or "message" not in case or check.check == "describe":
            return []
        encoding = check.check.split("-", 1)[1] if "-" in check.check else None
        if encoding not in self.codec.encodings:
            return []
        try:
            read = self.codec.decode(bytes.fromhex(check.actual), encoding, case, edition)
            diffs = self.codec.differences(case["message"], read, True, edition)
        except (ValueError, KeyError, TypeError, AttributeError):
            return []
        return [(d.path, d.expected, d.actual) for d in diffs if d.path is not None][:20]

    @staticmethod
    def capability(case: dict, request: Request) -> str | None:
        """What an answer to ``request`` shows (answered, for a valid case) or needs (a refusal): ``decode-<encoding>``
        (a roundtrip too) or ``encode-<encoding>``; None for a description."""
        if request.op == "describe":
            return None
        return f"{'encode' if request.op == 'encode' else 'decode'}-{request.encoding}"

    @staticmethod
    def unproven(check: CheckResult, group: str, capability: str) -> CheckResult:
        """A refusal from an implementation shown to read (or encode) no valid case of the group: not tested."""
        op, _, encoding = capability.partition("-")
        did = (f"reads no valid {group} frame ({encoding})" if op == "decode" else
               f"encodes no valid {group} message ({encoding})" if op == "encode" else
               f"neither reads nor encodes any valid {group} case: it does not implement {group}")
        return CheckResult(check.check, Verdict.UNSUPPORTED,
                           f"not tested: the implementation {did}, so its refusal shows nothing "
                           f"(it answered: {check.detail})", note=check.note)

    def failure(self, case: dict, edition: str, request: Request, detail: str, expected: bytes, actual: bytes | None,
                locate: bool = False) -> CheckResult:
        """A FAIL that keeps both frames and the differing byte ranges, named by field; ``locate`` adds where
        the frames first differ to ``detail``. The expected frame is laid out once."""
        spans = self._spans(expected, request.encoding, case, edition) if actual is not None else []
        if locate:
            detail += frame_difference(expected, actual, spans)
        return CheckResult(request.check, Verdict.FAIL, detail, expected=expected.hex(),
                           actual=None if actual is None else actual.hex(), diffs=byte_diffs(expected, actual, spans))

    def accepted(self, case: dict, edition: str, request: Request, answer, detail: str) -> CheckResult:
        """A FAIL for an invalid frame decoded: it keeps the frame given and the reference's encoding of what the
        implementation read from it (where that encodes), the differing bytes named by the fields of the latter."""
        read = self.reencoded(answer.message, request.encoding, edition)
        spans = [] if read is None else self._spans(read, request.encoding, case, edition)
        return CheckResult(request.check, Verdict.FAIL, detail, expected=request.frame.hex(),
                           actual=None if read is None else read.hex(), diffs=byte_diffs(request.frame, read, spans))

    def _spans(self, frame: bytes, encoding: str, case: dict, edition: str) -> list[Span]:
        try:
            return self.codec.layout(frame, encoding, case, edition)
        except ValueError:  # an expected frame the codec cannot lay out (e.g. an out-of-type alternative)
            return []

    def reencoded(self, message, encoding: str, edition: str) -> bytes | None:
        """The reference encoding of an implementation's decoded message, to show what it understood."""
        try:
            return self.codec.encode(message, encoding, edition)
        except (ValueError, KeyError, TypeError, AttributeError):
            return None


def _canonical(message) -> bytes | None:
    """The exact JSON bytes of a decoded message, or None where they could stand for another value (a null,
    which a NaN would also write) or cannot be written (a value of a subclass, an integer beyond 64 bits, a lone
    surrogate)."""
    if message is None:
        return None
    try:
        out = orjson.dumps(message, option=orjson.OPT_PASSTHROUGH_SUBCLASS)
    except TypeError:  # orjson.JSONEncodeError too
        return None
    return None if b"null" in out else out


def byte_diffs(expected: bytes, actual: bytes | None, spans: list[Span]) -> tuple[ByteDiff, ...]:
    """Runs of differing bytes, split at the field boundaries (``spans``) of the expected frame."""
    if actual is None:
        return ()
    owner = {i: s.path for s in spans for i in range(s.start, s.end)}
    out: list[ByteDiff] = []
    for i in range(max(len(expected), len(actual))):
        differs = i >= len(expected) or i >= len(actual) or expected[i] != actual[i]
        if not differs:
            continue
        name = owner.get(i, "beyond the expected frame" if i >= len(expected) else "unmapped")
        if out and out[-1].end == i and out[-1].field == name:
            out[-1] = ByteDiff(out[-1].start, i + 1, name)
        else:
            out.append(ByteDiff(i, i + 1, name))
    return tuple(out)


def frame_difference(expected: bytes, actual: bytes | None, spans: list[Span]) -> str:
    """Where two frames first differ, named by the field (of ``spans``) that owns the byte in the expected frame."""
    if actual is None:
        return "no frame"
    first = next((i for i, (a, b) in enumerate(zip(expected, actual)) if a != b), min(len(expected), len(actual)))
    if first == len(expected) == len(actual):
        return "identical"
    owner = next((s for s in spans if s.start <= first < s.end), None)
    where = f" = {owner.path} (bytes {owner.start}-{owner.end - 1})" if owner else ""
    return (f"{len(actual)} bytes, expected {len(expected)}; first difference at byte {first}{where}: "
            f"expected {expected[first:first + 8].hex(' ')}, got {actual[first:first + 8].hex(' ')}")
