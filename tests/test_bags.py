"""ROS 1 bags written with rosbags' writer from the corpus's realistic messages: under each edition and under a third
version, told apart connection by connection; a connection lying about its MD5, one type recorded by two editions,
other types counted and left alone; what is read is what rosbags reads; and hostile bags (no index, a damaged one,
cut short, a chunk larger than it says or than is read at once, lz4 without its package), each answered in one
line, never a traceback."""

from __future__ import annotations

import json
import struct
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rosbags.rosbag1 import Reader, ReaderError, Writer

from imc_conformance.capture.findings import Finding
from imc_conformance.capture.judge import CaptureJudge, Selection
from imc_conformance.capture.logs import Logged
from imc_conformance.cli import main
from imc_conformance.paths import VECTORS
from imc_conformance.suites import load_suite
from imc_conformance.capture import streams
from imc_conformance.suites.ros_acomms import bags, codec
from imc_conformance.suites.ros_acomms.msgtext import full_text, md5, parse_full_text, text_md5

SUITE = load_suite("ros_acomms")
EXAMPLES = [e["message"] for e in json.loads((VECTORS / "ros_acomms" / "examples.json").read_text())["examples"]]
SST = {"time": {"secs": 1700000000, "nsecs": 0}, "sst_version": 1, "in_water_spl_db": 131.5, "detector": 1,
       "num_samples": 2000, "summary_min": 101.0, "summary_lower_quartile": 110.0, "summary_median": 118.5,
       "summary_upper_quartile": 124.0, "summary_max": 131.5, "summary_len": 5}
STRING = ("std_msgs/String", "string data\n", "992ce8a1687cec8c8bd883ec73ca41d1")
T0 = 1_700_000_000 * 10**9


def connection(full: str, edition: str) -> tuple[str, str, str]:
    """(type, definition text, MD5) of a type as an edition has it."""
    view = SUITE.defs.edition(edition)
    return full, full_text(view, view[full]), md5(view, view[full])


def third_cst() -> tuple[str, str, str]:
    """CST as a version of ros_acomms_msgs neither edition is: a field added at its end."""
    _, text, _ = connection("ros_acomms_msgs/CST", "seed")
    text += "float32 noise_floor\n"
    return "ros_acomms_msgs/CST", text, text_md5(parse_full_text(text, "ros_acomms_msgs/CST"), "ros_acomms_msgs/CST")


def sst(edition: str) -> dict:
    fields = dict(SST)
    if edition == "9.0.0":
        fields["in_water_spl_dB"] = fields.pop("in_water_spl_db")
    return {"type": "ros_acomms_msgs/SST", "fields": fields}


def write_bag(path: Path, messages: list[tuple[str, tuple[str, str, str], bytes]], compression: str | None = None,
              chunk: int | None = None) -> Path:
    """A bag of (topic, (type, definition, MD5), bytes), one message every 0.1 s, written by rosbags."""
    writer = Writer(path)
    if compression:
        writer.set_compression(getattr(Writer.CompressionFormat, compression))
    if chunk:
        writer.chunk_threshold = chunk
    writer.open()
    made = {}
    for i, (topic, (full, text, digest), data) in enumerate(messages):
        if (topic, full, digest) not in made:
            made[(topic, full, digest)] = writer.add_connection(topic, full.replace("/", "/msg/"), msgdef=text,
                                                                md5sum=digest)
        writer.write(made[(topic, full, digest)], T0 + i * 10**8, data)
    writer.close()
    return path


def edition_bag(path: Path, edition: str, **options) -> Path:
    """The corpus's realistic messages and an SST, each type as ``edition`` defines it."""
    view = SUITE.defs.edition(edition)
    messages = [("/" + m["type"].split("/")[1].lower(), connection(m["type"], edition), codec.encode(view, m))
                for m in EXAMPLES + [sst(edition)]]
    return write_bag(path, messages, **options)


def run(*argv, capsys):
    code = main(["log", *map(str, argv)])
    return code, capsys.readouterr()


def judged(path: Path, capsys, *argv) -> tuple[int, dict, str]:
    out_json = path.with_suffix(".json")
    code, out = run(path, "--json", out_json, *argv, capsys=capsys)
    doc = json.loads(out_json.read_text())
    doc["verdicts"] = {c["id"]: c["verdict"] for m in doc["messages"] for c in m["cases"]}
    doc["details"] = {c["id"]: [k["detail"] for k in c["checks"]] for m in doc["messages"] for c in m["cases"]}
    return code, doc, out.err


def by_edition(doc: dict) -> str:
    return next(n for n in doc["notes"] if ": connections of ros_acomms_msgs types by the edition" in n)


# ---------------------------------------------------------------- editions told apart

def test_bags_of_both_editions_and_of_a_third_version_are_told_apart(tmp_path, capsys):
    code, doc, err = judged(edition_bag(tmp_path / "seed.bag", "seed"), capsys)
    assert code == 0 and set(doc["verdicts"].values()) == {"PASS"}, err
    assert doc["verdicts"]["ros_acomms/SST/capture/connection/definition"] == "PASS"
    assert by_edition(doc).endswith("seed and 9.0.0: /packet, /cst, /receivedpacket, /queuestatus, /modemack, "
                                    "/updatequeuedmessage ...; seed: /sst")
    code, doc, err = judged(edition_bag(tmp_path / "v9.bag", "9.0.0", compression="BZ2"), capsys)
    assert code == 0 and set(doc["verdicts"].values()) == {"PASS"}, err
    assert by_edition(doc).endswith("; 9.0.0: /sst")
    view = SUITE.defs.edition("seed")
    cst = next(m for m in EXAMPLES if m["type"] == "ros_acomms_msgs/CST")
    third = write_bag(tmp_path / "third.bag", [("/cst", third_cst(), codec.encode(view, cst) + struct.pack("<f", -80.5))]
                      * 3)
    code, doc, err = judged(third, capsys)
    assert code == 1 and by_edition(doc).endswith("no edition: /cst")
    assert doc["verdicts"] == {"ros_acomms/CST/capture/connection/definition": "FAIL",
                               "ros_acomms/CST/capture/connection/md5": "PASS",
                               "ros_acomms/CST/capture/frame/unknown-definition": "INCONCLUSIVE"}
    detail = doc["details"]["ros_acomms/CST/capture/connection/definition"][1]
    assert "its definition is that of no edition: edition seed: ros_acomms_msgs/CST: field 35 is 'float32 " \
           "noise_floor', expected missing; edition 9.0.0: ros_acomms_msgs/CST: field 35" in detail
    assert doc["details"]["ros_acomms/CST/capture/frame/unknown-definition"][0] == "3 frames"


def test_an_edition_asked_for_fails_the_connections_of_another(tmp_path, capsys):
    code, doc, _ = judged(edition_bag(tmp_path / "v9.bag", "9.0.0"), capsys, "--edition", "seed")
    assert code == 1 and doc["edition"] == "seed"
    assert {k for k, v in doc["verdicts"].items() if v != "PASS"} == {"ros_acomms/SST/capture/connection/definition"}
    assert "recorded with the definition of edition 9.0.0, not seed's: ros_acomms_msgs/SST: field 3 is 'float32 " \
           "in_water_spl_dB', expected 'float32 in_water_spl_db'" in doc["details"][
               "ros_acomms/SST/capture/connection/definition"][1]
    code, doc, _ = judged(tmp_path / "v9.bag", capsys, "--edition", "9.0.0")
    assert code == 0 and set(doc["verdicts"].values()) == {"PASS"}


def test_one_type_recorded_by_two_editions_cannot_connect(tmp_path, capsys):
    bag = write_bag(tmp_path / "mixed.bag", [
        ("/a/sst", connection("ros_acomms_msgs/SST", "seed"), codec.encode(SUITE.defs.edition("seed"), sst("seed"))),
        ("/b/sst", connection("ros_acomms_msgs/SST", "9.0.0"), codec.encode(SUITE.defs.edition("9.0.0"), sst("9.0.0")))])
    code, doc, _ = judged(bag, capsys)
    assert code == 1 and doc["verdicts"]["ros_acomms/SST/capture/frame/valid"] == "PASS"
    details = doc["details"]["ros_acomms/SST/capture/connection/definition"]
    assert details[:2] == ["1 connection", "1 connection"]
    assert details[2] == ("topic /b/sst: recorded with the definition of edition 9.0.0, where connection 0 (/a/sst) "
                          "was recorded with seed's: ROS 1 refuses to connect the two (their MD5s differ)")


def test_a_connection_lying_about_its_md5_and_one_that_does_not_read(tmp_path, capsys):
    full, text, _ = connection("ros_acomms_msgs/CST", "seed")
    cst = next(m for m in EXAMPLES if m["type"] == "ros_acomms_msgs/CST")
    data = codec.encode(SUITE.defs.edition("seed"), cst)
    lying = md5(SUITE.defs.edition("seed"), SUITE.defs.edition("seed")["ros_acomms_msgs/Packet"])
    bag = write_bag(tmp_path / "lies.bag", [("/cst", (full, text, lying), data),
                                            ("/bad", (full, "int8 version_number\nnot a line\n", "0" * 32), data)])
    code, doc, _ = judged(bag, capsys)
    details = doc["details"]
    assert code == 1 and details["ros_acomms/CST/capture/connection/md5"][1] == (
        f"topic /cst: its header says md5sum '{lying}', the MD5 of its own definition is 151d35f4fd7f782f15871b4c2f0a9d3c")
    assert details["ros_acomms/CST/capture/connection/definition"][2] == (
        "topic /bad: its definition text does not read: line 2: 'a line' is not a field name")
    assert doc["verdicts"]["ros_acomms/CST/capture/frame/unknown-definition"] == "INCONCLUSIVE"


def test_other_types_are_counted_and_left_alone(tmp_path, capsys):
    bag = write_bag(tmp_path / "other.bag", [("/chat", STRING, b"\x02\x00\x00\x00hi")] * 2 + [
        ("/packet", connection("ros_acomms_msgs/Packet", "seed"), codec.encode(SUITE.defs.edition("seed"), EXAMPLES[0]))])
    code, doc, _ = judged(bag, capsys)
    assert code == 0 and [m["name"] for m in doc["messages"]] == ["Packet"]
    assert "2 frames of 1 message the suite does not cover (counted, left alone): std_msgs/String (2)" in doc["notes"]


def test_megabytes_of_a_connections_text_are_shortened_in_the_report(tmp_path, capsys):
    full, _, _ = connection("ros_acomms_msgs/CST", "seed")
    long_topic, long_line = "/t" + "x" * 1_000_000, "int8 " + "y" * 1_000_000 + "!\n"
    bag = write_bag(tmp_path / "long.bag", [(long_topic, (full, long_line, "0" * 32), b"\x01"),
                                            ("/u", ("pkg/" + "Z" * 1_000_000, "int8 a\n", "0" * 32), b"\x01")])
    code, doc, _ = judged(bag, capsys)
    assert code == 1 and (tmp_path / "long.json").stat().st_size < 20_000
    detail = doc["details"]["ros_acomms/CST/capture/connection/definition"][1]
    assert detail.startswith(f"topic {long_topic[:bags.NAMED]}...: its definition text does not read: line 1: 'yyy")
    assert any(n.endswith(f"pkg/{'Z' * (bags.NAMED - 4)}... (1)") for n in doc["notes"])


def test_a_message_the_codec_refuses_fails_with_its_place(tmp_path, capsys):
    bag = write_bag(tmp_path / "short.bag", [("/packet", connection("ros_acomms_msgs/Packet", "seed"), b"\x01\x00")])
    code, doc, _ = judged(bag, capsys)
    detail = doc["details"]["ros_acomms/Packet/capture/frame/truncated"][1]
    assert code == 1 and "chunk at byte 4,109, byte " in detail and "of its data: byte 2: Packet.dest needs 2 bytes" in detail


# ---------------------------------------------------------------- the reading, against rosbags'

def read(path: Path, piece: int = 1 << 16) -> tuple[list, list[str], list[str]]:
    """(type, time in ns, bytes) of every message as the suite reads the bag (in pieces of ``piece`` bytes); its
    damage; its notes."""
    reader, damage = SUITE.log_reader(), []
    with open(path, "rb") as handle:
        units = list(reader.units(iter(lambda: handle.read(piece), b""), damage, path.name))
    out = []
    for unit in units:
        if unit.__class__ is Logged:
            out.append((unit.channel.full, round(unit.time * 1e9), unit.payload))
    return out, damage, reader.notes


@pytest.mark.parametrize("compression", [None, "BZ2", "LZ4"])
def test_what_is_read_is_what_rosbags_reads(tmp_path, compression):
    bag = edition_bag(tmp_path / "b.bag", "seed", compression=compression, chunk=300)
    ours, damage, _ = read(bag)
    with Reader(bag) as theirs:
        assert len(theirs.chunk_infos) > 2
        expected = [(c.msgtype.replace("/msg/", "/"), t, bytes(d)) for c, t, d in theirs.messages()]
    assert ours == expected and damage == []
    assert read(bag, 97)[:2] == (expected, [])  # the same, whatever the pieces the bytes come in


# ---------------------------------------------------------------- hostile bags

def index_pos(data: bytes) -> int:
    at = data.index(b"index_pos=", 13) + len(b"index_pos=")
    return at


def test_a_bag_without_its_index_is_read_and_says_so(tmp_path, capsys):
    data = bytearray(edition_bag(tmp_path / "b.bag", "seed", chunk=300).read_bytes())
    data[index_pos(data):index_pos(data) + 8] = bytes(8)  # as a recording that was never closed leaves it
    (tmp_path / "open.bag").write_bytes(bytes(data))
    with pytest.raises(ReaderError, match="not indexed"), Reader(tmp_path / "open.bag"):
        pass
    ours, damage, _ = read(tmp_path / "open.bag")
    assert len(ours) == 11 and damage == ["open.bag: it has no index (its recording was not closed: rosbag reindex "
                                          "would write one); read record by record"]
    code, out = run(tmp_path / "open.bag", capsys=capsys)
    assert code == 2 and out.err.count("\n") == 1 and "Traceback" not in out.err


def test_a_bag_whose_index_is_damaged_is_read_as_far_as_it_goes(tmp_path):
    data = edition_bag(tmp_path / "b.bag", "seed", chunk=300).read_bytes()
    at = struct.unpack_from("<Q", data, index_pos(data))[0]
    with Reader(tmp_path / "b.bag") as theirs:
        connections, chunks = len(theirs.connections), len(theirs.chunk_infos)
    (tmp_path / "cut-index.bag").write_bytes(data[:at + 40])
    ours, damage, _ = read(tmp_path / "cut-index.bag")
    assert len(ours) == 11 and damage == [f"cut-index.bag: its index is cut short at byte {at + 40:,}, inside the record "
                                          f"that begins at byte {at:,}: every chunk before it was read"]
    (tmp_path / "moved.bag").write_bytes(data[:index_pos(data)] + struct.pack("<Q", at + 3) + data[index_pos(data) + 8:])
    ours, damage, _ = read(tmp_path / "moved.bag")
    assert len(ours) == 11 and damage == [
        f"moved.bag: its index is damaged: its header says {connections} connections and {chunks} chunks at byte "
        f"{at + 3:,}; no record begins there, {connections} connections and {chunks} chunks are indexed (read record by "
        f"record: {chunks} chunks)"]


def test_a_bag_cut_short_is_read_up_to_the_cut(tmp_path, capsys):
    data = edition_bag(tmp_path / "b.bag", "seed", chunk=300).read_bytes()
    with Reader(tmp_path / "b.bag") as theirs:
        third = theirs.chunk_infos[2].pos
    (tmp_path / "cut.bag").write_bytes(data[:third + 50])
    ours, damage, _ = read(tmp_path / "cut.bag")
    assert damage == [f"cut.bag: the bag ends at byte {third + 50:,}, inside the record that begins at byte {third:,} "
                      "(cut short): read up to it"]
    with Reader(tmp_path / "b.bag") as theirs:
        assert ours == [(c.msgtype.replace("/msg/", "/"), t, bytes(d)) for c, t, d in theirs.messages()][:len(ours)]
    assert len(ours) >= 2
    code, out = run(tmp_path / "cut.bag", capsys=capsys)
    assert code == 2 and out.err.count("\n") == 1 and "cut short" in out.err


def test_a_chunk_larger_than_it_says_or_than_is_read_at_once(tmp_path, monkeypatch):
    data = bytearray(edition_bag(tmp_path / "b.bag", "seed", compression="BZ2").read_bytes())
    size = data.index(b"size=", 4096) + len(b"size=")
    data[size:size + 4] = struct.pack("<I", 100)  # it holds more than that once decompressed: a bomb, for all we know
    (tmp_path / "bomb.bag").write_bytes(bytes(data))
    _, damage, _ = read(tmp_path / "bomb.bag")
    assert damage == ["bomb.bag: the chunk at byte 4,109 holds more than the 100 bytes its header says: the bag is "
                      "read up to it"]
    monkeypatch.setattr(bags, "CHUNK_LIMIT", 99)
    _, damage, _ = read(tmp_path / "bomb.bag")
    assert "more than the 0 MB read at once" in damage[0]


def test_a_record_claiming_gigabytes_is_refused_before_it_is_read(tmp_path):
    data = bytearray(edition_bag(tmp_path / "b.bag", "seed").read_bytes())
    data[4109:4113] = struct.pack("<I", 0xFFFFFFF0)  # the first chunk's header length
    (tmp_path / "huge.bag").write_bytes(bytes(data))
    _, damage, _ = read(tmp_path / "huge.bag")
    assert damage == ["huge.bag: the record at byte 4,109 claims a 4,294,967,280-byte header, more than the 4 MB read "
                      "at once: the bag is read up to it"]


def test_an_lz4_chunk_without_its_package_is_one_line(tmp_path, monkeypatch):
    edition_bag(tmp_path / "b.bag", "seed", compression="LZ4")
    monkeypatch.setitem(sys.modules, "lz4.frame", None)
    _, damage, _ = read(tmp_path / "b.bag")
    assert damage == ["b.bag: the chunk at byte 4,109 is lz4-compressed: reading it needs the lz4 package, which the "
                      "suite's ros extra installs: the bag is read up to it"]


def test_a_bag_for_another_suite_is_one_line(tmp_path, capsys):
    edition_bag(tmp_path / "b.bag", "seed")
    code, out = run(tmp_path / "b.bag", "--suite", "imc", capsys=capsys)
    assert code == 2 and "b.bag: not a LSF log (it starts 23524f5342414720)" in out.err and out.err.count("\n") == 1


@pytest.fixture(scope="module")
def small_bags(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bags")
    return [edition_bag(folder / f"{c}.bag", "seed", compression=c, chunk=200).read_bytes() for c in (None, "BZ2", "LZ4")]


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(which=st.integers(0, 2), edits=st.lists(st.tuples(st.integers(0, 20_000), st.integers(0, 255)), max_size=8),
       cut=st.integers(0, 6_000))
def test_a_damaged_bag_is_read_or_refused_never_a_crash(small_bags, which, edits, cut):
    buf = bytearray(small_bags[which])
    for at, value in edits:
        buf[at % len(buf)] = value
    buf = bytes(buf[:max(1, len(buf) - cut)])
    reader, damage = SUITE.log_reader(), []
    judge = CaptureJudge("ros_acomms", reader.rules, reader.edition, Selection(), log=True)
    for unit in reader.units(iter([buf]), damage, "x"):
        if unit.__class__ is Finding:
            judge.found(unit)
        else:
            judge.logged(unit)
    judge.result(implementation="fuzz", started="2026-01-01T00:00:00+00:00", duration=0.0, strict=False, title="ros")
    assert all("\n" not in line for line in damage)


# ---------------------------------------------------------------- bombs and bounds, in bags written by hand

def record(fields: dict[str, bytes], data: bytes) -> bytes:
    """A bag record: its header's ``name=value`` fields, each after its length, then its data."""
    head = b"".join(struct.pack("<I", len(k) + 1 + len(v)) + k.encode() + b"=" + v for k, v in fields.items())
    return struct.pack("<I", len(head)) + head + struct.pack("<I", len(data)) + data


def conn_record(conn: int, full: str, definition: str, digest: str) -> bytes:
    described = {"type": full.encode(), "md5sum": digest.encode(), "message_definition": definition.encode()}
    return record({"op": b"\x07", "conn": struct.pack("<I", conn), "topic": b"/t"},
                  b"".join(struct.pack("<I", len(k) + 1 + len(v)) + k.encode() + b"=" + v for k, v in described.items()))


def message_record(conn: int, data: bytes, t: int = 1_700_000_000) -> bytes:
    return record({"op": b"\x02", "conn": struct.pack("<I", conn), "time": struct.pack("<II", t, 0)}, data)


def chunk_record(content: bytes, compression: str = "bz2") -> bytes:
    import bz2

    data = bz2.compress(content, 9) if compression == "bz2" else content
    return record({"op": b"\x05", "compression": compression.encode(), "size": struct.pack("<I", len(content))}, data)


def test_a_bag_bomb_of_many_chunks_is_refused_at_the_floor(tmp_path, monkeypatch):
    """Chunks of repeated messages, 256 kB each from a few hundred bytes: the chunks' output is taken against the
    bag's bytes read, as a compressed stream's, and refused once past the floor (lowered here to 1 MB)."""
    monkeypatch.setattr(streams, "BOMB_FLOOR", 1 << 20)
    message = message_record(0, bytes(1000))
    content = conn_record(0, *STRING) + message * ((256 << 10) // len(message))
    chunk = chunk_record(content)
    (tmp_path / "bomb.bag").write_bytes(bags.MAGIC + chunk * 100)
    assert (tmp_path / "bomb.bag").stat().st_size < 100 * 500
    ours, damage, _ = read(tmp_path / "bomb.bag")
    assert len(damage) == 1 and "more than 200 times their size (no bag compresses so well: a decompression bomb?): " \
                                "refused from there" in damage[0]
    per_chunk = content.count(message)
    assert len(ours) <= 5 * per_chunk  # the floor's worth of chunks, not the hundred


def test_a_definition_inside_a_chunk_is_bounded_as_outside(tmp_path, monkeypatch):
    monkeypatch.setattr(bags, "HEADER_LIMIT", 1 << 20)
    full, text, digest = connection("ros_acomms_msgs/Packet", "seed")
    huge = text + "# " + "x" * (3 << 19) + "\n"  # 1.5 MB of comment
    (tmp_path / "def.bag").write_bytes(bags.MAGIC + chunk_record(conn_record(0, full, huge, digest), "none"))
    _, damage, _ = read(tmp_path / "def.bag")
    assert len(damage) == 1 and damage[0].startswith("def.bag: the connection record in the chunk at byte 13 (byte 0 "
                                                     "of its data) holds 1,573,")
    assert damage[0].endswith(" bytes, more than the 1 MB read at once: the bag is read up to it")


def test_a_message_too_large_to_decode_whole_is_not_judged(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(bags, "MESSAGE_LIMIT", 1000)
    bag = write_bag(tmp_path / "large.bag", [("/packet", connection("ros_acomms_msgs/Packet", "seed"), bytes(1001))])
    code, doc, _ = judged(bag, capsys)
    case = "ros_acomms/Packet/capture/frame/too-large-to-decode"
    assert code == 0 and doc["verdicts"][case] == "INCONCLUSIVE"
    assert "1,001 bytes, more than the 0 MB a message is decoded whole up to: not judged" in doc["details"][case][1]


def test_a_damaged_bz2_chunk_is_described_as_libbz2_says(tmp_path):
    import bz2

    content = conn_record(0, *STRING) + b"".join(message_record(0, bytes([i]) * 300) for i in range(200))
    data = bytearray(bz2.compress(content))
    data[len(data) // 2] ^= 0xFF
    chunk = record({"op": b"\x05", "compression": b"bz2", "size": struct.pack("<I", 100)}, bytes(data))
    (tmp_path / "bad.bag").write_bytes(bags.MAGIC + chunk)
    _, damage, _ = read(tmp_path / "bad.bag")
    assert damage == ["bad.bag: the chunk at byte 13 is damaged bz2 data (Invalid data stream): the bag is read up to "
                      "it"]


def test_src_dst_and_host_do_not_apply_to_a_bag(tmp_path, capsys):
    bag = edition_bag(tmp_path / "b.bag", "seed")
    for option in ("--src", "--dst", "--host"):
        code, out = run(bag, option, "30", capsys=capsys)
        err = out.err
        assert code == 2 and err.count("\n") == 1, err
        assert "--src, --dst and --host do not apply to a ROS 1 bag: its messages name no system" in err


def test_a_definition_text_too_large_to_read_is_not_judged(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(bags, "DEFINITION_LIMIT", 4096)
    full, text, digest = connection("ros_acomms_msgs/Packet", "seed")
    lines = "".join(f"uint8 f{i}\n" for i in range(1000))
    bag = write_bag(tmp_path / "lines.bag", [("/packet", (full, text + lines, digest), b"\x00" * 8)])
    code, doc, _ = judged(bag, capsys)
    definition = "ros_acomms/Packet/capture/connection/definition"
    assert doc["verdicts"][definition] == "INCONCLUSIVE" and code == 2  # nothing was judged
    assert f"its definition text holds {len(text + lines):,} characters, more than the 4 kB read" in \
        doc["details"][definition][1]
    assert doc["verdicts"]["ros_acomms/Packet/capture/frame/unknown-definition"] == "INCONCLUSIVE"
