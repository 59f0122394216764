"""The ros_acomms definitions are the package's: every MD5 and definition text agrees with what genpy (the
canonical ROS 1 Python code) and rosbags compute, the emitted .msg and .srv files reproduce every MD5, and
a definition text is read back field by field, with a clear error for a bad one."""

from __future__ import annotations

import pytest

from imc_conformance.cli import main
from imc_conformance.suites.ros_acomms.definitions import DefinitionError, load_definitions
from imc_conformance.suites.ros_acomms.msgtext import (expected_types, full_text, md5, parse_full_text, parse_msg,
                                                       service_md5, text_differences)

DEFS = load_definitions()
EDITIONS = DEFS.editions
# MD5s ros-acomms.md states (identical in the seed and in 9.0.0), checked with genpy and rosbags there
KNOWN = {"std_msgs/Header": "2176decaecbce78abc3b96ef049fabed", "ros_acomms_msgs/CST": "151d35f4fd7f782f15871b4c2f0a9d3c",
         "ros_acomms_msgs/Packet": "3d7233b74904ec0798f99e4da729526d",
         "ros_acomms_msgs/QueueStatus": "8e4c357ec598339bf318415ff790f649",
         "ros_acomms_msgs/ReceivedPacket": "9c0e7a7479a7f58e908447df9e845ec8"}


def types_of(edition: str) -> list[str]:
    view = DEFS.edition(edition)
    return [full for full, m in view.types.items() if not m.definition.auxiliary]


def test_the_seed_has_38_types_and_9_0_0_35():
    assert len(types_of("seed")) == 38 and len(types_of("9.0.0")) == 35
    assert {t.kind for t in DEFS.suite_types} == {"msg", "request", "response"}


@pytest.mark.parametrize("edition", EDITIONS)
def test_known_md5s(edition):
    view = DEFS.edition(edition)
    assert {full: md5(view, view[full]) for full in KNOWN} == KNOWN


@pytest.mark.parametrize("edition", EDITIONS)
@pytest.mark.parametrize("adapter", ["rosbags", "genpy"])
def test_every_md5_and_definition_is_the_implementations(edition, adapter, request):
    from imc_conformance.adapters.genpy_adapter import GenpyAdapter
    from imc_conformance.adapters.rosbags_adapter import RosbagsAdapter
    implementation = {"rosbags": RosbagsAdapter, "genpy": GenpyAdapter}[adapter](edition=edition)
    view = DEFS.edition(edition)
    for full in types_of(edition):
        told = implementation.describe("ros_acomms", type=full)
        assert told["md5"] == md5(view, view[full]), full
        described = parse_full_text(told["definition"], full)
        assert text_differences(expected_types(view, view[full]), described) == [], full


def test_service_md5s_are_genpys(genpy_adapter):
    view = DEFS.edition("seed")
    services = {t.service for t in DEFS.suite_types if t.service}
    assert len(services) == 5
    for service in services:
        request, response = (view[f"ros_acomms_msgs/{service}{half}"] for half in ("Request", "Response"))
        told = genpy_adapter.describe("ros_acomms", type=f"ros_acomms_msgs/{service}Request")
        assert told["service_md5"] == service_md5(view, request, response), service


@pytest.mark.parametrize("edition", EDITIONS)
def test_the_emitted_package_files_reproduce_every_md5(edition, tmp_path, capsys):
    from imc_conformance.adapters.genpy_adapter import GenpyAdapter
    from imc_conformance.adapters.rosbags_adapter import RosbagsAdapter
    assert main(["ros-msg-files", str(tmp_path), "--edition", edition]) == 0
    assert (tmp_path / "msg" / "CST.msg").read_text().startswith("int8 version_number\n")
    view = DEFS.edition(edition)
    emitted_types = [f for f in types_of(edition)  # a service missing a half in the edition is not emitted
                     if view[f].definition.kind == "msg" or (tmp_path / "srv" / f"{view[f].definition.service}.srv").exists()]
    for implementation in (RosbagsAdapter(msgs=str(tmp_path)), GenpyAdapter(msgs=str(tmp_path))):
        for full in emitted_types:
            assert implementation.describe("ros_acomms", type=full)["md5"] == md5(view, view[full]), full


def test_9_0_0_changes_exactly_the_types_ros_acomms_md_determines():
    seed, v9 = (DEFS.edition(e) for e in EDITIONS)
    changed = {full for full in types_of("9.0.0") if full_text(seed, seed[full]) != full_text(v9, v9[full])}
    assert changed == {f"ros_acomms_msgs/{t}" for t in ("SST", "LinkStatsFeedback", "GetNextPacketDataRequest",
                                                         "GetNextQueuedMessageRequest")}
    assert set(types_of("seed")) - set(types_of("9.0.0")) == {
        f"ros_acomms_msgs/{t}" for t in ("SoundSpeedProfile", "GetNextPacketDataResponse", "PingModemRequest")}
    assert md5(v9, v9["ros_acomms_msgs/SST"]) == "69e24d5bc402c8bc26c014f76173d62f"


@pytest.mark.parametrize("text, where", [
    ("int16 src\nint16\n", "line 2: 'int16' is not 'type name'"),
    ("int16 src\nfloat32 9lives\n", "line 2: '9lives' is not a field name"),
    ("int16 src\nstring X = 3 4\nbool[x] flags\n", "line 3: 'bool[x]' is not a type"),
])
def test_a_bad_msg_text_names_its_line(text, where):
    with pytest.raises(DefinitionError, match=None) as error:
        parse_msg(text, "ros_acomms_msgs")
    assert where in str(error.value)


def test_a_team_package_with_a_syntax_error_is_a_one_line_usage_error(tmp_path, capsys):
    (tmp_path / "msg").mkdir()
    (tmp_path / "msg" / "Packet.msg").write_text("int16 src\nint16 dest with spaces\n")
    code = main(["run", "--suite", "ros_acomms", "--adapter", "rosbags", "--adapter-arg", f"msgs={tmp_path}",
                 "--no-progress", "--message", "Packet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "cannot create the adapter" in err[0]
    assert "msg/Packet.msg: line 2: 'dest with spaces' is not a field name" in err[0]


def test_comments_and_layout_do_not_change_a_described_definition():
    view = DEFS.edition("seed")
    full = "ros_acomms_msgs/Packet"
    text = "# a packet\n" + full_text(view, view[full]).replace("int16 dest\n", "int16   dest  # the destination\n\n")
    assert text_differences(expected_types(view, view[full]), parse_full_text(text, full)) == []
