"""The relay: its link model, its judging of both sides on virtual time (the reference node as the vehicle, the
suite's peer logic as the console), and its refusals."""

from __future__ import annotations

import re
from collections import Counter

import pytest

from imc_conformance.capture.datagrams import Datagram
from imc_conformance.cli import main
from imc_conformance.core.verdicts import Verdict
from imc_conformance.relay.core import SIDES
from imc_conformance.relay.impairment import Impairment, Link, parse
from imc_conformance.suites.imc import codec
from relay_harness import CONSOLE, FACING, SUITE, VEHICLE, Console, judge, simulate

LOSSY = {side: Impairment(loss=0.3, delay=2.0) for side in SIDES}


def verdicts(result, side: str) -> dict[str, Verdict]:
    """A side's case verdicts by their id as a capture files it (``relay/<side>/by-<blamed>/`` taken out)."""
    marker = f"/relay/{side}/"
    return {re.sub(r"/relay/[a-z]+/by-[a-z]+/", "/capture/", c.id): c.verdict for c in result.cases if marker in c.id}


def test_a_clean_relay_judges_each_side_as_watch_judges_the_traffic(tmp_path):
    """Each side's verdicts equal those of a watcher of the conversation, and those ``pcap`` gives on the relay's own
    recording."""
    from imc_conformance.capture.recording import Recorder
    from imc_conformance.capture.records import records

    log: list = []
    recorder = Recorder(tmp_path / "relay.pcapng", {}, prefix="imc-conformance relay ")
    _, console, result = simulate(90, log=log, record=recorder.record)
    recorder.close(complete=False)
    assert console.answered > 20
    watch = judge()  # what watch judges of the conversation: every datagram each side sent, as it was sent
    for number, (t, side, what, data, _) in enumerate(log, 1):
        if what == "sent":
            src, dst = (CONSOLE, FACING["console"]) if side == "console" else (VEHICLE, FACING["vehicle"])
            watch.received(Datagram(number, t, src[0], src[1], dst[0], dst[1], data))
    watched = watch.result(implementation="watch", started="", duration=0.0, strict=False, title="", until=90)
    expected = {c.id: c.verdict for c in watched.cases}
    assert any("/exchange/" in case for case in expected) and set(expected.values()) == {Verdict.PASS}
    recorded = judge()
    for record in records((tmp_path / "relay.pcapng").read_bytes()):
        recorded.feed(record)
    replayed = recorded.result(implementation="pcap", started="", duration=0.0, strict=False, title="", until=90)
    assert {c.id: c.verdict for c in replayed.cases} == expected
    for side in SIDES:  # each side's exchanges as watch judges them
        assert {case: v for case, v in verdicts(result, side).items() if "/frame/" not in case} == \
            {case: v for case, v in expected.items() if "/frame/" not in case}
    frames = [c for c in result.cases if "/frame/" in c.id]  # the frames each side sent, each under it
    assert all(re.search(r"/relay/([a-z]+)/by-\1/frame/", c.id) for c in frames)
    assert {re.sub(r"/relay/[a-z]+/by-[a-z]+/", "/capture/", c.id) for c in frames} == \
        {case for case in expected if "/frame/" in case}
    assert sum(ch.verdict is Verdict.PASS and int(ch.detail.split()[0].replace(",", "")) for c in frames
               for ch in c.checks if ch.check == "count") == len(log) - sum(1 for entry in log if entry[2] == "received")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_correct_pair_gets_no_fail_under_30_percent_loss_and_2_s_delay(seed):
    relay, console, result = simulate(180, LOSSY, seed=seed)
    counts = Counter(c.verdict for c in result.cases)
    assert counts[Verdict.FAIL] == 0, [c.id for c in result.cases if c.verdict is Verdict.FAIL]
    assert all(relay.counts[side]["lost (loss)"] > 20 for side in SIDES)
    vehicle = verdicts(result, "vehicle")
    assert vehicle["imc/AcousticSystemsQuery/capture/exchange/acoustic-systems/to-requester"] is Verdict.PASS
    resent = [c for c in result.cases if "/request/resend-after-loss/" in c.id]
    assert resent and any(ch.verdict is Verdict.PASS for c in resent for ch in c.checks)


def test_requests_lost_on_a_link_that_is_down_are_nobodys_failure():
    down = {"console": Impairment(down=((20.0, 40.0),)), "vehicle": Impairment()}
    relay, _, result = simulate(90, down)
    assert relay.counts["console"]["the link was down"] > 10
    assert not [c.id for c in result.cases if c.verdict is Verdict.FAIL]
    assert not [c for c in result.cases if "/relay/vehicle/" in c.id and c.verdict is not Verdict.PASS]


def test_a_console_that_never_resends_a_query_is_caught():
    _, _, result = simulate(180, LOSSY, console=Console(tries=1))
    resent = [c for c in result.cases if "/request/resend-after-loss/" in c.id]
    checks = [ch for c in resent for ch in c.checks if ch.check != "count"]
    assert {ch.verdict for ch in checks} <= {Verdict.IMPL_DEFINED, Verdict.INCONCLUSIVE}  # a reading the seeds leave open
    assert all("(open reading resend-after-loss)" in ch.detail for ch in checks if ch.verdict is Verdict.IMPL_DEFINED)
    assert all("before it stopped" in ch.detail for ch in checks if ch.verdict is Verdict.INCONCLUSIVE)
    assert sum(ch.verdict is Verdict.IMPL_DEFINED for ch in checks) >= 5
    assert not [c for c in result.cases if c.verdict is Verdict.FAIL]


@pytest.mark.parametrize("impair", [{}, LOSSY], ids=["clean", "lossy"])
def test_a_vehicle_answering_the_wrong_requester_is_caught(impair):
    _, _, result = simulate(120, impair, broken="replies-to-first-client")
    failed = {c.id for c in result.cases if c.verdict is Verdict.FAIL and "/relay/vehicle/" in c.id}
    assert "imc/AcousticSystemsQuery/relay/vehicle/by-vehicle/exchange/acoustic-systems/answered" in failed


def test_the_recording_holds_what_each_side_sent_and_received(tmp_path):
    from imc_conformance.capture.recording import Recorder
    from imc_conformance.capture.records import records

    recorder = Recorder(tmp_path / "relay.pcapng", {"impairment": "loss"}, prefix="imc-conformance relay ")
    relay, _, _ = simulate(30, {side: Impairment(loss=0.3, duplicate=0.2) for side in SIDES}, record=recorder.record)
    recorder.close(complete=False)
    sections: list[str] = []
    comments = Counter(r.comment.split(" (")[0] for r in records((tmp_path / "relay.pcapng").read_bytes(), sections))
    assert sections == ['imc-conformance relay {"impairment": "loss"}']
    for side in SIDES:
        other = "vehicle" if side == "console" else "console"
        assert comments[f"{side} sent"] == relay.counts[side]["sent"]
        assert comments[f"{other} received"] == relay.counts[side]["delivered"] > relay.counts[side]["sent"] * 0.7


def test_the_link_is_reproducible_from_its_seed():
    spec = parse("loss=0.2,burst=3,delay=0.5,jitter=0.2,distribution=normal,duplicate=0.1,reorder=0.1,corrupt=0.1,"
                 "rate=9600,down=5-6")

    def fates(seed):
        link = Link(spec, seed, "console")
        return [(f.dropped, [(round(t, 9), d) for t, d, _ in f.copies]) for f in
                (link.carry(i * 0.05, bytes(range(40))) for i in range(2000))]

    assert fates(7) == fates(7) != fates(8)
    kinds = Counter(f[0] or ("copies", len(f[1])) for f in fates(7))
    assert kinds["the link was down"] == 20 and kinds[("copies", 2)] > 50 and kinds["lost (loss)"] > 200


def test_the_link_does_what_each_setting_says():
    data = bytes(range(100))
    link = Link(Impairment(loss=0.3), 1, "x")
    lost = sum(link.carry(i, data).dropped is not None for i in range(10000))
    assert 2700 < lost < 3300
    bursty = Link(Impairment(loss=0.3, burst=5), 1, "x")
    runs, run = [], 0
    for i in range(20000):
        if bursty.carry(i, data).dropped:
            run += 1
        elif run:
            runs, run = runs + [run], 0
    assert 4 < sum(runs) / len(runs) < 6 and 0.25 < sum(runs) / 20000 < 0.35
    corrupt = Link(Impairment(corrupt=0.5), 1, "x")
    changed = [f.copies[0][1] for f in (corrupt.carry(i, data) for i in range(200)) if "byte" in f.copies[0][2]]
    assert changed and all(sum(a != b for a, b in zip(c, data)) == 1 and len(c) == len(data) for c in changed)
    capped = Link(Impairment(rate=8000), 1, "x")  # 1,000 bytes a second
    assert [round(capped.carry(0.0, data).copies[0][0], 6) for _ in range(3)] == [0.1, 0.2, 0.3]
    late = Link(Impairment(delay=2.0, jitter=1.0, distribution="exponential", reorder=0.5, hold=0.5), 1, "x")
    times = [late.carry(0.0, data).copies[0][0] for _ in range(500)]
    assert min(times) >= 2.0 and any(t > 3.0 for t in times)


@pytest.mark.parametrize("text, message", [
    ("loss=1", "loss='1': a share in [0, 1)"), ("lose=0.1", "'lose=0.1': expected NAME=VALUE"),
    ("burst=3", "burst needs a loss rate"), ("down=5-2", "START < END"), ("distribution=pareto", "one of uniform"),
    ("delay=nan", "a number in [0, 1e6]")])
def test_a_mistaken_impairment_is_one_line(text, message):
    with pytest.raises(ValueError, match=None) as caught:
        parse(text)
    assert message in str(caught.value) and "\n" not in str(caught.value)


@pytest.mark.parametrize("argv, message", [
    (["udp://10.0.0.1:6010", "--vehicle", "udp://127.0.0.1:6002"], "10.0.0.1 is not a loopback address"),
    (["udp://127.0.0.1:6010", "--vehicle", "udp://224.0.75.69:6002"], "224.0.75.69 is not a loopback address"),
    (["udp://127.0.0.1:6010", "--vehicle", "udp://255.255.255.255:6002"], "is not a loopback address"),
    (["udp://127.0.0.1:6010", "--vehicle", "udp://127.0.0.1:6002", "--via", "0.0.0.0:0"], "0.0.0.0 is not a loopback"),
    (["udp://127.0.0.1:6010", "--vehicle", "udp://127.0.0.1:6002", "--to-console", "corrupt=2"], "--to-console: corrupt"),
    (["udp://127.0.0.1:6010", "--vehicle", "udp://127.0.0.1:6010", "--duration", "0.1"],
     "is the relay's own socket (relay)"),
    (["udp://127.0.0.1:6010", "--vehicle", "udp://127.0.0.1:6011", "--via", "127.0.0.1:6011", "--duration", "0.1"],
     "is the relay's own socket (--via)"),
    (["udp://127.0.0.1:6010", "--vehicle", "udp://127.255.255.255:6002"], "the loopback network's broadcast address"),
    (["udp://127.0.0.1:6010", "--vehicle", "udp://127.0.0.0:6002"], "the loopback network's network address"),
    (["udp://127.255.255.255:6010", "--vehicle", "udp://127.0.0.1:6002"], "the loopback network's broadcast address"),
    (["udp://127.0.0.1:6010", "--vehicle", "udp://127.0.0.1:6002", "--impair", "rate=0"],
     "rate=0: a cap in bits per second above 0"),
    (["udp://127.0.0.1:6010", "--vehicle", "udp://[::1]:6002"],
     "--vehicle udp://[::1]:6002 and the relay's address udp://127.0.0.1:6010 are not of the same address family: "
     "give --via [::1]:0"),
])
def test_the_relay_refuses_in_one_line(argv, message, capsys):
    assert main(["relay", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_an_announce_is_changed_to_name_the_relay_and_nothing_else_is():
    rewrite = SUITE.relay_hooks()["rewrite"]
    header = {"timestamp": 1.0, "src": 0x4C10, "src_ent": 0, "dst": 0, "dst_ent": 0}
    announce = codec.encode(SUITE.defs, {"abbrev": "Announce", "header": header, "fields": {
        "sys_name": "c", "sys_type": 0, "owner": 0xFFFF, "lat": 0.0, "lon": 0.0, "height": 0.0,
        "services": "imc+udp://10.0.0.5:6001/;imc+info://0.0.0.0/version/5.4.30"}}, "be")
    changed = codec.decode(SUITE.defs, rewrite(announce, ("127.0.0.1", 6011)))
    assert changed["fields"]["services"] == "imc+udp://127.0.0.1:6011/;imc+info://0.0.0.0/version/5.4.30"
    assert codec.byte_order_of(rewrite(announce, ("127.0.0.1", 6011))) == "be"
    query = codec.encode(SUITE.defs, {"abbrev": "AcousticSystemsQuery", "header": header, "fields": {}})
    assert rewrite(query, ("127.0.0.1", 6011)) is None and rewrite(b"\x54\xfe\x97", ("127.0.0.1", 1)) is None


def _free_port() -> int:
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def test_a_vehicle_that_sends_nothing_is_one_line_and_judged_on_nothing(tmp_path, capsys):
    """No vehicle listens: the console's datagrams could not all be sent (none counted delivered as well), one line
    says nothing came from the vehicle, exit 2, and no case blames the vehicle."""
    import json
    import socket
    import threading

    listen, vehicle = _free_port(), _free_port()
    header = {"timestamp": 1.0, "src": 0x4C10, "src_ent": 0, "dst": 0x1F, "dst_ent": 0xFF}
    query = codec.encode(SUITE.defs, {"abbrev": "AcousticSystemsQuery", "header": header, "fields": {}}, "le")
    stop = threading.Event()

    def console():
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            while not stop.wait(0.1):
                sock.sendto(query, ("127.0.0.1", listen))

    sender = threading.Thread(target=console, daemon=True)
    sender.start()
    try:
        code = main(["relay", f"udp://127.0.0.1:{listen}", "--vehicle", f"udp://127.0.0.1:{vehicle}", "--duration",
                     "1.5", "--json", str(tmp_path / "r.json")])
    finally:
        stop.set()
        sender.join()
    err = capsys.readouterr().err
    assert code == 2
    said = [line for line in err.splitlines() if "nothing came from the vehicle" in line]
    assert len(said) == 1 and f"udp://127.0.0.1:{vehicle}" in said[0]
    result = json.loads((tmp_path / "r.json").read_text())
    ids = [case["id"] for message in result["messages"] for case in message["cases"]]
    assert ids and not [i for i in ids if "/by-vehicle/" in i]
    line = next(n for n in result["notes"] if n.startswith("console to vehicle:"))
    sent = int(line.split(": ")[1].split()[0])
    delivered = int(line.split(", ")[1].split()[0])
    unsent = sum(int(part.split()[0]) for part in line.split("; ")[1].split(", ") if "could not be sent" in part) \
        if "could not be sent" in line else 0
    assert sent > 3 and delivered + unsent == sent, line


def test_what_a_direction_holds_in_flight_is_bounded_in_bytes():
    """A console flooding 65,507-byte datagrams through a 2 s delay: the relay holds at most IN_FLIGHT_LIMIT bytes on
    the way, the rest is a loss of the link, counted, and its memory stays within the bound, not the flood's size."""
    import tracemalloc

    from imc_conformance.relay.core import IN_FLIGHT_LIMIT, Relay

    links = {side: Link(Impairment(delay=2.0), 0, side) for side in SIDES}
    relay = Relay({side: judge() for side in SIDES}, links, FACING, {"console": CONSOLE, "vehicle": VEHICLE},
                  **SUITE.relay_hooks())
    n, size = 1600, 65_507
    tracemalloc.start()
    try:
        for i in range(n):
            relay.inbound(i / n, "console", i.to_bytes(4, "little") * (size // 4) + b"end", CONSOLE)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    held = sum(len(entry[3]) for entry in relay.queue)
    assert held == relay.in_flight["console"] <= IN_FLIGHT_LIMIT < n * size
    dropped = relay.counts["console"][f"over the relay's {IN_FLIGHT_LIMIT >> 20} MiB in flight (a full buffer)"]
    assert dropped == n - len(relay.queue) > 0
    assert peak < IN_FLIGHT_LIMIT + n * size // 4  # the flood is 105 MB; the relay holds its bound and little else
    assert all(len(relay.judges[side].tracker.losses) == 1 for side in SIDES)  # the drops are one time, not a list
    assert len(relay.due(10.0)) == n - dropped and relay.in_flight["console"] == 0
    assert any(f"{dropped} over the relay's" in note for note in relay.notes())


def test_a_console_sending_from_many_ports_is_answered_where_its_announce_says():
    """imcpy sends each datagram from a socket of its own and asks, in its Announce, to be answered at its listening
    socket: the relay takes the console's datagrams from any port that speaks as one of its systems, and sends the
    vehicle's where the Announce said; a stranger speaking as another system is not the console."""
    from imc_conformance.relay.core import Relay

    links = {side: Link(Impairment(), 0, side) for side in SIDES}
    relay = Relay({side: judge() for side in SIDES}, links, FACING, {"console": None, "vehicle": VEHICLE},
                  **SUITE.relay_hooks())

    def frame(abbrev: str, src: int, fields: dict) -> bytes:
        header = {"timestamp": 1.0, "src": src, "src_ent": 0, "dst": 0xFFFF, "dst_ent": 0xFF}
        return codec.encode(SUITE.defs, {"abbrev": abbrev, "header": header, "fields": fields}, "le")

    announce = frame("Announce", 0x3334, {"sys_name": "ccu-imcpy", "sys_type": 0, "owner": 0xFFFF, "lat": 0.0,
                                          "lon": 0.0, "height": 0.0, "services": "imc+udp://127.0.0.1:7777/"})
    query, stranger = frame("AcousticSystemsQuery", 0x3334, {}), frame("AcousticSystemsQuery", 0x9999, {})
    assert relay.accepts("console", ("127.0.0.1", 40001), announce)
    relay.inbound(0.0, "console", announce, ("127.0.0.1", 40001))
    assert relay.endpoints["console"] == ("127.0.0.1", 7777)
    assert relay.accepts("console", ("127.0.0.1", 40002), query)
    assert not relay.accepts("console", ("127.0.0.1", 40003), stranger)
    assert not relay.accepts("vehicle", ("127.0.0.1", 40004), query) and relay.accepts("vehicle", VEHICLE, query)


@pytest.mark.parametrize("services", ["imc+udp://127.255.255.255:7777/", "imc+udp://127.0.0.0:7777/"])
def test_an_announce_naming_the_loopback_broadcast_is_not_where_the_relay_sends(services):
    """The relay sends to one host on loopback only: an Announce asking to be answered at the loopback network's
    broadcast or network address is answered where its datagrams come from."""
    from imc_conformance.relay.core import Relay

    links = {side: Link(Impairment(), 0, side) for side in SIDES}
    relay = Relay({side: judge() for side in SIDES}, links, FACING, {"console": None, "vehicle": VEHICLE},
                  **SUITE.relay_hooks())
    header = {"timestamp": 1.0, "src": 0x3334, "src_ent": 0, "dst": 0xFFFF, "dst_ent": 0xFF}
    announce = codec.encode(SUITE.defs, {"abbrev": "Announce", "header": header, "fields": {
        "sys_name": "ccu", "sys_type": 0, "owner": 0xFFFF, "lat": 0.0, "lon": 0.0, "height": 0.0,
        "services": services}}, "le")
    relay.inbound(0.0, "console", announce, ("127.0.0.1", 40001))
    assert relay.endpoints["console"] == ("127.0.0.1", 40001)
