"""The second hardening round: the live link, ``serve``, captures and the files a user gives, under hostile and
careless use. Each test names the item of the issue it reproduces; everything runs on virtual time or loopback,
with bounded floods. The hostile node's modes are in tests/hostile_node.py."""

from __future__ import annotations

import json
import select
import signal
import socket
import subprocess
import sys

import pytest

from imc_conformance.capture.recording import ABOUT, read_about
from imc_conformance.capture.writing import PcapNgWriter
from imc_conformance.cli import build_parser, main
from imc_conformance.core.runner import run_cases
from imc_conformance.core.verdicts import Verdict
from imc_conformance.limits import NESTING_LIMIT, STARTUP_MAX, TIME_SCALE_MAX
from imc_conformance.sessions.datagram import DatagramSession
from imc_conformance.sessions.udp import parse_endpoint
from imc_conformance.sessions.virtual import VirtualLink
from imc_conformance.suites.imc import codec
from imc_conformance.suites.imc.node import ReferenceNode
from imc_conformance.suites.imc.node.node import CONTACT_TTL, MAX_CONTACTS
from imc_conformance.suites.imc.peer import DEFAULT_SYSTEM, ImcPeer
from hostile_node import MODES, HostileNode, nested_frame
from live_harness import EVERYTHING, NODE, OWN, scenario_cases

EDITION = "imc-5.4.30"
QUICK = ("imc/AcousticSystemsQuery/scenario/reply", "imc/IridiumMsgTx/scenario/status", "imc/LblConfig/scenario/get-cfg",
         "imc/HistoricDataQuery/scenario/query")


def one_line(err: str) -> None:
    assert err.count("\n") == 1 and "Traceback" not in err, err


def hostile_run(suite, cases, mode: str, capacity: int | None = None, dst: int | None = None, ids=None, broken=None):
    """The scenarios (all, or ``ids``) against the hostile node (made of a broken one, if ``broken``) on virtual
    time."""
    node = HostileNode(ReferenceNode(suite.defs, suite.behaviour, edition=EDITION, address=NODE, broken=broken), mode)
    link = VirtualLink(node, NODE, OWN, capacity=capacity)
    peer = ImcPeer(suite.defs, system=DEFAULT_SYSTEM, node=dst, service=f"imc+udp://{OWN[0]}:{OWN[1]}/", host=NODE[0],
                   epoch=link.epoch)
    hello = {"implementation": f"hostile node ({mode})", "suites": ["imc"], "byte_orders": ["le", "be"],
             "kinds": ["scenario"]}
    session = DatagramSession(link, peer, suite.wire, hello, startup=10.0)
    options = dict(EVERYTHING, profile=suite.profile("seed"), corpus=())
    chosen = [c for c in scenario_cases(cases) if ids is None or c.id in ids]
    result = run_cases(session, suite, chosen, edition=EDITION, adapter="virtual", options=options, clock=link.now,
                       started="2026-01-01T00:00:00+00:00")
    return result, link, node


# ---------------------------------------------------------------- a correct node behind a hostile link: never FAIL

@pytest.mark.parametrize("mode", [m for m in MODES if m != "echo-only"])
def test_a_correct_node_behind_a_hostile_link_never_fails(suite, cases, mode):
    result, link, node = hostile_run(suite, cases, mode, capacity=1000 if mode == "flood" else None)
    failed = {c.id: c.detail for c in result.cases if c.verdict not in (Verdict.PASS, Verdict.INCONCLUSIVE, Verdict.IMPL_DEFINED)}
    assert failed == {}
    unjudged = [c for c in result.cases if c.verdict is Verdict.INCONCLUSIVE]
    assert unjudged, "the hostility was not seen at all"
    text = json.dumps(result.to_dict())
    assert {"deep-nesting": "not judged: nested-too-deep", "flood": "datagram(s) before the session could read them",
            "impostor-announce": "an Announce with the session's id", "impostor-replies": "answers a request this run never sent"
            }[mode] in text


def test_item_11_a_flood_loses_replies_and_the_report_gives_the_count(suite, cases):
    result, link, _ = hostile_run(suite, cases, "flood", capacity=1000)
    assert link.lost >= 4000
    assert any(f"{link.lost} datagrams were dropped by the kernel" in n for n in result.notes)
    lost = [c for c in result.cases if c.verdict is Verdict.INCONCLUSIVE and "kernel dropped" in c.detail]
    assert lost


def test_item_12_a_frame_nested_too_deep_is_inconclusive_live_and_in_its_recording(suite, cases, tmp_path):
    result, link, _ = hostile_run(suite, cases, "deep-nesting", ids=QUICK)
    live = [k for c in result.cases for k in c.checks if "nested-too-deep" in k.detail]
    assert live and all(k.verdict is Verdict.INCONCLUSIVE for k in live)
    frame = nested_frame(300)
    from imc_conformance.capture.records import records
    from imc_conformance.capture.judge import CaptureJudge, Selection
    from imc_conformance.capture.writing import PCAP_HEADER, ethernet_udp, pcap_record
    capture = PCAP_HEADER + pcap_record(1.0, ethernet_udp("10.0.0.1", 6002, "10.0.0.2", 6001, frame))
    judge = CaptureJudge("imc", suite.capture_rules(), EDITION, Selection(None, frozenset()))
    for record in records(capture):
        judge.feed(record)
    judged = judge.result(implementation="capture", started="", duration=0.0, strict=False, title="IMC")
    case = next(c for c in judged.cases if c.id.endswith("/frame/nested-too-deep"))
    assert case.verdict is Verdict.INCONCLUSIVE and case.id.startswith("imc/AcousticMessage/")


def test_item_16_the_session_own_frames_never_count_as_the_node(suite, cases):
    result, link, _ = hostile_run(suite, cases, "echo-only", dst=0x00A0, ids=QUICK)
    assert any("no valid frame ever came from hostile node" in n for n in result.notes)
    assert {c.verdict for c in result.cases} == {Verdict.INCONCLUSIVE}
    assert result.exit_code() == 2


@pytest.mark.parametrize("broken", ["two-terminals", "status-after-terminal", "wrong-system"])
def test_item_15_while_another_system_uses_the_session_id_no_failure_is_judged(suite, cases, broken):
    """Its replies and the session's cannot be told apart (an AcousticOperation's only correlation is the system's
    name): from the moment the impostor shows, a scenario's failures are INCONCLUSIVE, those of scenarios that
    ended before it stay."""
    result, _, _ = hostile_run(suite, cases, "impostor-announce", broken=broken)
    assert any(c.verdict is Verdict.INCONCLUSIVE and "session's id" in c.detail for c in result.cases)
    for case in result.cases:
        if case.verdict is Verdict.FAIL:
            assert not any(e["event"] == "impaired" for e in case.timeline), case.id


def test_item_15_a_reply_off_by_a_little_is_the_node_s_mistake_not_an_impostor(suite, cases):
    """A node that does not echo (req_id + 1) still fails: only numbers far from every request's are strangers'."""
    from live_harness import run_virtual
    result, _ = run_virtual(suite, [c for c in cases if c.id == "imc/AcousticRequest/scenario/range"],
                            EDITION, broken="req-id-not-echoed")
    assert result.cases[0].verdict is Verdict.FAIL
    assert not any("identity" in n for n in result.notes)


# ---------------------------------------------------------------- 1 and 6: serve under a hostile client

def announce(defs, src: int, services: str, t: float = 0.0) -> bytes:
    fields = {"sys_name": "client", "sys_type": 0, "owner": 0xFFFF, "lat": 0.0, "lon": 0.0, "height": 0.0,
              "services": services}
    header = {"timestamp": 1.7e9 + t, "src": src, "src_ent": 0, "dst": 0, "dst_ent": 0xFF}
    return codec.encode(defs, {"abbrev": "Announce", "header": header, "fields": fields})


def query(defs, src: int) -> bytes:
    header = {"timestamp": 1.7e9, "src": src, "src_ent": 1, "dst": 0x00A0, "dst_ent": 0xFF}
    return codec.encode(defs, {"abbrev": "AcousticSystemsQuery", "header": header, "fields": {}})


def reference(suite) -> ReferenceNode:
    return ReferenceNode(suite.defs, suite.behaviour, edition=EDITION, address=NODE)


def test_item_1_the_node_drops_a_frame_nested_too_deep_counts_it_and_keeps_serving(suite):
    node = reference(suite)
    node.receive(0.0, announce(suite.defs, 7, "imc+udp://127.0.0.1:7000/"), ("127.0.0.1", 7000))
    node.receive(0.1, nested_frame(400, src=7, dst=0x00A0), ("127.0.0.1", 7000))
    node.receive(0.2, query(suite.defs, 7), ("127.0.0.1", 7000))
    sent = [codec.decode(suite.defs, d)["abbrev"] for _, d in node.due(1.0)]
    assert node.unjudged == 1 and "AcousticSystems" in sent


def test_item_6_a_service_naming_a_host_is_ignored_and_nothing_is_resolved(suite, monkeypatch):
    def no_lookups(*args, **kwargs):
        raise AssertionError("the node resolved a name")
    monkeypatch.setattr(socket, "getaddrinfo", no_lookups)
    node = reference(suite)
    node.receive(0.0, announce(suite.defs, 7, "imc+udp://blackhole.example:6000/"), ("127.0.0.1", 7000))
    assert node.contacts == {} and node.refused == 1 and node.due(5.0) == []


def test_item_6_the_contact_table_is_bounded_and_a_talking_contact_keeps_its_place(suite):
    node = reference(suite)
    node.receive(0.0, announce(suite.defs, 7, "imc+udp://127.0.0.1:7000/"), ("127.0.0.1", 7000))
    for src in range(1000, 21000):  # 20,000 spoofed Announces
        node.receive(0.5, announce(suite.defs, src, f"imc+udp://127.0.0.1:{src % 60000 + 1}/"), ("127.0.0.1", 9))
    assert len(node.contacts) == MAX_CONTACTS and 7 in node.contacts
    beats = [a for a, d in node.due(1.0) if codec.decode(suite.defs, d)["abbrev"] == "Heartbeat"]
    assert len(beats) <= MAX_CONTACTS
    node.receive(20.0, query(suite.defs, 7), ("127.0.0.1", 7000))  # the client keeps talking
    node.due(CONTACT_TTL + 10.0)
    assert list(node.contacts) == [7]  # the spoofed contacts, silent since, are forgotten


@pytest.fixture
def serve():
    """``imc-conformance serve`` on a free loopback port (its URL), stopped and waited for at the end."""
    proc = subprocess.Popen([sys.executable, "-m", "imc_conformance.cli", "serve", "--port", "0"],
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    line = proc.stderr.readline()
    yield line.split(" on ", 1)[1].split(";")[0]
    proc.send_signal(signal.SIGINT)
    assert proc.wait(timeout=10) == 0
    assert "dropped" in proc.stderr.read()


def test_item_1_serve_survives_a_frame_nested_400_deep(serve, suite):
    host, port = parse_endpoint(serve, "serve")
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        me = sock.getsockname()
        sock.sendto(announce(suite.defs, 7, f"imc+udp://{me[0]}:{me[1]}/"), (host, port))
        sock.sendto(nested_frame(400, src=7, dst=0x00A0), (host, port))
        sock.sendto(query(suite.defs, 7), (host, port))
        got = []
        while "AcousticSystems" not in got and select.select([sock], [], [], 10)[0]:
            got.append(codec.decode(suite.defs, sock.recv(65535))["abbrev"])
    assert "AcousticSystems" in got


# ---------------------------------------------------------------- 2, 13, 14: one set of bounds; addresses

def test_item_2_the_command_line_accepts_what_a_recording_reads_back_and_nothing_more():
    parser = build_parser()
    args = parser.parse_args(["run", "--target", "udp://127.0.0.1:6002", "--time-scale", str(TIME_SCALE_MAX),
                              "--startup", str(STARTUP_MAX)])
    about = {"suite": "imc", "edition": EDITION, "cases": [], "target": args.target, "src": None, "dst": None,
             "startup": args.startup, "params": {}, "effects": [], "time_scale": args.time_scale, "profile": "seed",
             "claims": None, "first_unique": 7}
    assert read_about([ABOUT + json.dumps(about)]) == about
    for flag, value in (("--time-scale", TIME_SCALE_MAX * 1.5), ("--startup", STARTUP_MAX + 400)):
        with pytest.raises(SystemExit):
            parser.parse_args(["run", "--target", "udp://127.0.0.1:6002", flag, str(value)])
        with pytest.raises(ValueError, match="damaged"):
            read_about([ABOUT + json.dumps(dict(about, **{flag[2:].replace("-", "_"): value}))])


def test_item_13_a_target_on_port_0_is_refused(capsys):
    assert main(["run", "--target", "udp://127.0.0.1:0"]) == 2
    err = capsys.readouterr().err
    one_line(err)
    assert "port 0" in err


def test_item_14_serve_prints_an_ipv6_url_that_run_reads():
    try:
        with socket.socket(socket.AF_INET6, socket.SOCK_DGRAM) as probe:
            probe.bind(("::1", 0))
    except OSError:
        pytest.skip("no IPv6 loopback here")
    proc = subprocess.Popen([sys.executable, "-m", "imc_conformance.cli", "serve", "--host", "::1", "--port", "0"],
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        url = proc.stderr.readline().split(" on ", 1)[1].split(";")[0]
        assert url.startswith("udp://[::1]:") and parse_endpoint(url, "--target")[0] == "::1"
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=10)


# ---------------------------------------------------------------- 3, 4, 9: what the suite reads and writes

def test_item_3_a_recording_that_cannot_be_written_is_one_line_and_the_reports_go_on(serve, tmp_path, capsys):
    report = tmp_path / "r.json"
    code = main(["run", "--target", serve, "--no-progress", "--id", "imc/AcousticSystemsQuery/scenario/reply",
                 "--pcap", "/dev/full", "--json", str(report)])
    err = capsys.readouterr().err
    assert code == 2 and report.exists() and set(json.loads(report.read_text())["summary"]) == {"PASS"}
    one_line(err)
    assert "cannot write the pcapng to /dev/full: No space left on device" in err


@pytest.mark.parametrize("argv", [["run", "--claims", "{}", "--target", "udp://127.0.0.1:9"], ["run", "--waivers", "{}"],
                                  ["report", "{}"], ["run", "--vectors", "{}"]])
@pytest.mark.parametrize("given", ["/dev/zero", "deep"])
def test_items_4_and_9_every_file_read_is_bounded_in_size_and_nesting(argv, given, tmp_path, capsys):
    if given == "deep":
        path = tmp_path / "deep.json"
        path.write_text("[" * 100_000)
        if argv[1] == "--vectors":  # a suite folder whose data file nests too deeply
            (tmp_path / "cases").mkdir()
            (tmp_path / "cases" / "x.json").write_text("[" * 100_000)
            path = tmp_path
    else:
        path = given
        if argv[1] == "--vectors":
            (tmp_path / "cases").mkdir()
            (tmp_path / "cases" / "x.json").symlink_to("/dev/zero")
            path = tmp_path
    assert main([a.replace("{}", str(path)) for a in argv]) == 2
    err = capsys.readouterr().err
    one_line(err)
    assert ("nested too deeply" if given == "deep" else "larger than 256 MB") in err


def test_item_9_a_pcapng_section_comment_nested_30000_deep_is_one_line(tmp_path, capsys, defs):
    path = tmp_path / "r.pcapng"
    with open(path, "wb") as out:
        writer = PcapNgWriter(out, ABOUT + "[" * 30_000)
        writer.write(1.0, ("127.0.0.1", 6001), ("127.0.0.1", 6002), query(defs, 7), "x")
    assert main(["pcap", str(path)]) == 2
    err = capsys.readouterr().err
    one_line(err)
    assert "nested too deeply" in err


def test_the_reference_codec_refuses_to_encode_nesting_beyond_its_bound(defs):
    message = {"abbrev": "LblRange", "fields": {"id": 1, "range": 1.0}}
    for _ in range(NESTING_LIMIT + 1):
        message = {"abbrev": "AcousticMessage", "fields": {"message": message}}
    with pytest.raises(codec.EncodeError, match="nested deeper"):
        codec.encode(defs, message)


# ---------------------------------------------------------------- 10: ros-msg-files

@pytest.mark.parametrize("where, why", [
    ("file", "is not a folder"),
    ("file/sub", "cannot write under"),
    ("/proc/imc-conformance-nowhere", "cannot write under"),
])
def test_item_10_ros_msg_files_into_a_place_that_is_no_folder_is_one_line(tmp_path, capsys, where, why):
    (tmp_path / "file").write_text("x")
    target = where if where.startswith("/") else str(tmp_path / where)
    assert main(["ros-msg-files", target]) == 2
    err = capsys.readouterr().err
    one_line(err)
    assert why in err


def test_item_10_ros_msg_files_never_overwrites_unasked_nor_writes_through_a_link(tmp_path, capsys):
    folder = tmp_path / "pkg"
    assert main(["ros-msg-files", str(folder)]) == 0
    assert main(["ros-msg-files", str(folder)]) == 2
    assert "give --replace" in capsys.readouterr().err
    victim = tmp_path / "victim"
    victim.write_text("keep me")
    (folder / "msg" / "CST.msg").unlink()
    (folder / "msg" / "CST.msg").symlink_to(victim)
    assert main(["ros-msg-files", str(folder), "--replace"]) == 0
    assert victim.read_text() == "keep me" and not (folder / "msg" / "CST.msg").is_symlink()
    (folder / "srv").rename(tmp_path / "elsewhere")
    (folder / "srv").symlink_to(tmp_path / "elsewhere")
    assert main(["ros-msg-files", str(folder), "--replace"]) == 2
    assert "is a symbolic link" in capsys.readouterr().err


# ---------------------------------------------------------------- 11: watch states its losses

def test_item_11_watch_states_what_the_kernel_dropped(tmp_path, defs):
    """A bounded flood at a watched socket: the report's count of judged datagrams plus the kernel's drops is what was
    sent, and any loss is stated (whether the kernel drops any depends on the machine; the statement must not)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    report = tmp_path / "w.json"
    watch = subprocess.Popen([sys.executable, "-m", "imc_conformance.cli", "watch", f"udp://127.0.0.1:{port}",
                              "--duration", "8", "--json", str(report)], stderr=subprocess.PIPE, text=True)
    assert "watching" in watch.stderr.readline()
    beat = codec.encode(defs, {"abbrev": "Heartbeat", "header": {"timestamp": 1.7e9, "src": 5, "src_ent": 0,
                                                                 "dst": 0xFFFF, "dst_ent": 0xFF}, "fields": {}})
    sent = 50_000
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as out:
        for _ in range(sent):
            out.sendto(beat, ("127.0.0.1", port))
    watch.communicate(timeout=60)
    doc = json.loads(report.read_text())
    judged = int(doc["notes"][0].split(" records")[0].replace(",", ""))
    dropped = [n for n in doc["notes"] if "dropped by the kernel" in n]
    lost = int(dropped[0].split(" datagrams")[0].replace(",", "")) if dropped else 0
    assert judged + lost == sent, doc["notes"]
