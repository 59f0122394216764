"""The byte-vector kind's judge: nothing an implementation answers can crash it, and misbehaving adapters are
blamed as such."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from imc_conformance.core.session import Answer, Request
from imc_conformance.core.verdicts import Verdict
from imc_conformance.files import open_corpus

SUITE, _CASES = open_corpus("imc")
KIND = SUITE.kinds["vector"]
CASES = [c.data for c in _CASES if c.kind == "vector"]
EDITION = "imc-5.4.30"
SAMPLE = [c for c in CASES if c["id"].startswith(("imc/LblConfig/", "imc/AcousticOperation/", "imc/Announce/"))]


def judge(case, request, answer):
    return KIND.judge(case, EDITION, request, answer)

json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=True) | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.sampled_from(
        ["abbrev", "header", "fields", "id", "range", "beacons", "timestamp", "msg", "hex", "x"]), inner, max_size=5),
    max_leaves=20)


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(SAMPLE), st.data())
def test_any_answer_gets_a_verdict(case, data):
    requests = KIND.plan(case, EDITION, {"le", "be"})
    request = data.draw(st.sampled_from(requests))
    message = data.draw(json_values | st.fixed_dictionaries({"abbrev": st.just(case["id"].split("/")[1]),
                                                             "header": json_values, "fields": json_values}))
    frame = data.draw(st.binary(max_size=64))
    kind = data.draw(st.sampled_from(["ok", "rejected", "unsupported", "crash", "timeout", "adapter-error"]))
    rule = data.draw(st.none() | st.text(max_size=10))
    answer = Answer(kind, frame=frame if request.op != "decode" else None,
                    message=message if request.op == "decode" else None, reason="<b>x</b>", rule=rule)
    result = judge(case, request, answer)
    assert isinstance(result.verdict, Verdict) and isinstance(result.detail, str)


def test_an_unknown_message_name_is_an_adapter_error():
    case = next(c for c in CASES if c["id"] == "imc/AcousticOperation/realistic/crosscheck")
    answer = dict(case["message"], fields=dict(case["message"]["fields"], msg={"abbrev": "NoSuchMessage", "fields": {}}))
    result = judge(case, Request("decode-le", "decode", "le"), Answer("ok", message=answer))
    assert result.verdict is Verdict.ADAPTER_ERROR and "'NoSuchMessage'" in result.detail


def test_an_unhashable_message_name_is_an_adapter_error_too():
    case = next(c for c in CASES if c["id"] == "imc/AcousticOperation/realistic/crosscheck")
    answer = dict(case["message"], fields=dict(case["message"]["fields"], msg={"abbrev": ["x"], "fields": {}}))
    result = judge(case, Request("decode-le", "decode", "le"), Answer("ok", message=answer))
    assert result.verdict is Verdict.ADAPTER_ERROR and "['x']" in result.detail


def test_an_accepted_invalid_frame_fails_whatever_the_answer_says():
    case = next(c for c in CASES if c["id"] == "imc/LblRange/unknown-id/999/le")
    answer = Answer("ok", message={"abbrev": "Unknown", "header": {}, "fields": {}})  # what pyimclsts answers
    assert judge(case, Request("decode-le", "decode", "le"), answer).verdict is Verdict.FAIL


def test_a_wrong_rule_is_non_strict_and_no_rule_passes():
    case = next(c for c in CASES if c["id"] == "imc/LblRange/crc/footer-first-byte/le")
    request = Request("decode-le", "decode", "le")
    assert judge(case, request, Answer("rejected", rule="sync")).verdict is Verdict.NON_STRICT
    assert judge(case, request, Answer("rejected", rule="crc")).verdict is Verdict.PASS
    assert judge(case, request, Answer("rejected")).verdict is Verdict.PASS


def test_encode_failures_name_the_differing_field():
    case = next(c for c in CASES if c["id"] == "imc/LblRange/realistic/crosscheck")
    frame = bytearray.fromhex(case["frames"]["le"])
    frame[23] ^= 0xFF
    result = judge(case, Request("encode-le", "encode", "le"), Answer("ok", frame=bytes(frame)))
    assert result.verdict is Verdict.FAIL
    assert [(d.start, d.end, d.field) for d in result.diffs][0] == (23, 24, "LblRange.range")
    assert "first difference at byte 23 = LblRange.range (bytes 21-24)" in result.detail


def _read_text(value, codec: str, as_hex: bool):
    """A decoded message with every {"hex"} text read by a reader using ``codec`` ("utf-8" replacing undecodable
    bytes with U+FFFD: a lossy reader; "latin-1": a wrong one), answered as a JSON string or as {"hex"} of the text's
    UTF-8 bytes."""
    if isinstance(value, dict) and set(value) == {"hex"}:
        text = bytes.fromhex(value["hex"]).decode(codec, "replace")
        return {"hex": text.encode("utf-8").hex()} if as_hex else text
    if isinstance(value, dict):
        return {k: _read_text(v, codec, as_hex) for k, v in value.items()}
    if isinstance(value, list):
        return [_read_text(v, codec, as_hex) for v in value]
    return value


def test_lossy_text_gets_one_verdict_whether_answered_as_a_string_or_as_hex():
    """The contract makes a string and {"hex"} of its UTF-8 bytes equal: a reader replacing undecodable text bytes
    is lossy (IMPL_DEFINED) in either form, in both suites, and a Latin-1 reader FAILs in either form."""
    ros, ros_cases = open_corpus("ros_acomms")
    judged = 0
    ros_vectors = [c.data for c in ros_cases if c.kind == "vector"]
    for kind, edition, cases in ((KIND, EDITION, CASES), (ros.kinds["vector"], ros.editions[0], ros_vectors)):
        lossy = [c for c in cases if c.get("expect") == "acceptable" and "lossy" in {o["outcome"] for o in c["outcomes"]}
                 and _read_text(c["message"], "utf-8", False) != c["message"]]
        for case in lossy:
            request = next(r for r in kind.plan(case, edition, set()) if r.op == "decode")
            for codec, verdict in (("utf-8", Verdict.IMPL_DEFINED), ("latin-1", Verdict.FAIL)):
                answers = [_read_text(case["message"], codec, as_hex) for as_hex in (False, True)]
                if codec == "latin-1" and answers[0] == _read_text(case["message"], "utf-8", False):
                    continue  # bytes Latin-1 and UTF-8 read alike
                verdicts = [kind.judge(case, edition, request, Answer("ok", message=m)).verdict for m in answers]
                assert verdicts == [verdict, verdict], (case["id"], codec, verdicts)
            judged += 1
    assert judged >= 20, judged
