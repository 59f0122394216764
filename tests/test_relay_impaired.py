"""The relay's verdicts over an impaired link, on virtual time (the reference node as the vehicle, the suite's peer
logic as the console): a wrong answer that arrived is judged whatever the link lost; what the relay lost, delayed or
duplicated is never read as either side's behaviour."""

from __future__ import annotations

from collections import Counter

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from imc_conformance.core.verdicts import Verdict
from imc_conformance.relay.core import SIDES
from imc_conformance.relay.impairment import Impairment
from relay_harness import RANGES, SUITE, Console, simulate

IMPAIRED = {side: Impairment(loss=0.3, delay=1.0, duplicate=0.1, reorder=0.1) for side in SIDES}
# breaks that answer wrongly, and the case each FAILs, blaming the vehicle, on the sides the wrong answer reached
WRONG = {"req-id-not-echoed": ("HistoricDataQuery", "exchange/historic-data-query/echo-req_id", SIDES),
         "broadcast-replies": ("AcousticSystemsQuery", "exchange/acoustic-systems/to-requester", SIDES),
         "malformed-reply": ("AcousticSystems", "frame/size-exceeds-data", ("vehicle",))}
REVERSE_RANGE = next(e.value for e in SUITE.defs.by_abbrev["AcousticOperation"].fields[0].enum_values
                     if e.abbrev == "REVERSE_RANGE")


def failed(result) -> set[str]:
    return {c.id for c in result.cases if c.verdict is Verdict.FAIL}


def not_passed(result) -> dict[str, Verdict]:
    return {c.id: c.verdict for c in result.cases if c.verdict is not Verdict.PASS}


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("broken", [*WRONG, "replies-to-first-client", "from-other-system"])
def test_a_break_that_answers_wrongly_fails_through_a_link_losing_30_percent(broken, seed):
    _, _, result = simulate(150, IMPAIRED, seed=seed, broken=broken)
    if broken in WRONG:
        message, case, sides = WRONG[broken]
        assert {f"imc/{message}/relay/{side}/by-vehicle/{case}" for side in sides} <= failed(result)
    else:  # its replies answer no request of their requester: the vehicle's side sees them unanswered
        assert any("/relay/vehicle/by-vehicle/exchange/" in case and case.endswith("/answered")
                   for case in failed(result))
    assert not [case for case in failed(result) if "/by-console/" in case]


@settings(max_examples=40, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(loss=st.floats(0, 0.45), delay=st.floats(0, 3), duplicate=st.floats(0, 0.3), reorder=st.floats(0, 0.3),
       jitter=st.floats(0, 1), distribution=st.sampled_from(["uniform", "normal", "exponential"]),
       seed=st.integers(0, 2**16), broken=st.sampled_from([None, *WRONG]))
def test_on_any_impairment_a_correct_pair_gets_no_fail_and_a_broken_one_its_break(loss, delay, duplicate, reorder,
                                                                                   jitter, distribution, seed, broken):
    link = Impairment(loss=loss, delay=delay, duplicate=duplicate, reorder=reorder, jitter=jitter,
                      distribution=distribution)
    _, _, result = simulate(120, {side: link for side in SIDES}, seed=seed, broken=broken)
    if broken is None:
        assert not failed(result)
    else:
        message, case, _ = WRONG[broken]
        assert f"imc/{message}/relay/vehicle/by-vehicle/{case}" in failed(result)
        assert all("/by-vehicle/" in c for c in failed(result))


def test_a_late_reply_to_a_resent_query_is_no_wrong_echo():
    """A query resent while the first was open, its bound passed before the reply to the resend came (a normal
    jitter's tail): that reply is late, not a wrong echo of the requester's next query (found by a sweep)."""
    link = Impairment(loss=0.185, delay=2.628, jitter=0.558, distribution="normal", duplicate=0.0095, reorder=0.118)
    _, _, result = simulate(120, {side: link for side in SIDES}, seed=33413)
    assert not failed(result)


def test_a_vehicle_answering_in_1_2_s_through_2_s_of_delay_each_way_gets_no_fail():
    """The console sees each reply 5.2 s after its query, past the 5 s bound; the relay added 4 s of that."""
    _, console, result = simulate(120, {side: Impairment(delay=2.0) for side in SIDES}, after=1.2)
    assert console.answered > 20
    assert not failed(result)
    answered = [c for c in result.cases if "/relay/console/by-vehicle/exchange/" in c.id and c.id.endswith("/answered")]
    assert len(answered) == 3 and all(ch.verdict is not Verdict.PASS or int(ch.detail.split()[0]) > 10
                                      for c in answered for ch in c.checks if ch.check == "count")
    late = [ch.detail for c in answered for ch in c.checks if ch.verdict is Verdict.INCONCLUSIVE and ch.check != "count"]
    assert late and all("(and the 4 s a relay added to the way)" in detail for detail in late)  # the run's end cut them short


def test_a_request_the_relay_duplicated_gives_no_non_strict_and_no_reading():
    """A RANGE delivered twice: the vehicle answers the copy (BUSY, the modem busy with the first) and each copy's
    states are the copy's, not states after the terminal one."""
    copies = 0
    for seed in range(3):
        relay, _, result = simulate(90, {"console": Impairment(duplicate=0.5), "vehicle": Impairment()}, seed=seed,
                                    console=Console(tries=1, queries=RANGES))
        copies += relay.counts["console"]["duplicated"]
        assert not {case: v for case, v in not_passed(result).items() if v is not Verdict.INCONCLUSIVE}
    assert copies > 10


def test_a_request_the_relay_lost_is_never_a_reading():
    """A REVERSE_RANGE may go unanswered (an open reading); one the relay lost is not judged at all."""
    query = (("AcousticOperation", {"op": REVERSE_RANGE, "system": "imc-peer-1", "range": 0.0, "msg": None}),)
    _, _, clean = simulate(90, {}, console=Console(tries=1, queries=query))
    assert not not_passed(clean)
    for seed in range(3):
        relay, _, result = simulate(90, {side: Impairment(loss=0.3, delay=1.0) for side in SIDES}, seed=seed,
                                    console=Console(tries=1, queries=query))
        assert relay.counts["console"]["lost (loss)"] > 3
        assert set(not_passed(result).values()) == {Verdict.INCONCLUSIVE}
        readings = [c for c in result.cases if "/reading/" in c.id]
        assert all("not judged: the relay did not deliver datagram" in ch.detail for c in readings for ch in c.checks
                   if ch.check != "count")


def test_every_lost_query_is_read_once_its_window_ended():
    """Each query the relay lost is read (resent, or not within twice its bound); one lost too near the end is
    INCONCLUSIVE, never read as no resend."""
    log: list = []
    relay, _, result = simulate(100, {"console": Impairment(loss=0.3), "vehicle": Impairment()}, seed=3, log=log)
    received = Counter(data for _, side, what, data, _ in log if what == "received" and side == "vehicle")
    queries = ("AcousticSystemsQuery", "LblConfig", "HistoricDataQuery")
    from imc_conformance.suites.imc import codec

    lost = [t for t, side, what, data, _ in log if side == "console" and what == "sent" and not received[data]
            and codec.decode(SUITE.defs, data)["abbrev"] in queries]
    resend = [c for c in result.cases if "/request/resend-after-loss/" in c.id]
    assert all("/relay/console/by-console/" in c.id for c in resend)
    counted = Counter()
    for c in resend:
        for ch in c.checks:
            if ch.check == "count":
                counted[ch.verdict] += int(ch.detail.split()[0])
    assert sum(counted.values()) == len(lost) > 5
    last = [ch for c in resend for ch in c.checks if ch.verdict is Verdict.INCONCLUSIVE and ch.check != "count"]
    assert all("before it stopped" in ch.detail for ch in last)
