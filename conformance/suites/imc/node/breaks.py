"""The broken behaviours of the reference node (``serve --break NAME``): each breaks one rule a scenario
checks, so the test suite can show that the rule is caught (mutant implementations)."""

BREAKS = {
    "req-id-not-echoed": "AcousticStatus, IridiumTxStatus and HistoricDataQuery replies carry another req_id",
    "type-not-echoed": "AcousticStatus replies carry type MSG whatever the request's type",
    "seq-not-echoed": "SmsState replies carry another sequence number",
    "wrong-system": "AcousticOperation replies name another system than the request's",
    "status-after-terminal": "an IN_PROGRESS AcousticStatus follows the terminal status",
    "two-terminals": "AcousticStatus SENT/RANGE_RECEIVED is followed by ERROR",
    "no-terminal": "AcousticStatus stops at IN_PROGRESS",
    "wrong-kind-terminal": "a RANGE AcousticOperation ends in MSG_DONE",
    "no-cur-cfg": "GET_CFG is never answered",
    "other-beacons": "CUR_CFG leaves out the last stored beacon",
    "ignores-big-endian": "big-endian frames are dropped",
    "big-endian-le-crc": "replies are big-endian with the CRC in little-endian order",
    "late": "every reply comes 30 s late",
    "dies-after-raw": "after one valid AcousticRequest of type RAW, acoustic requests go unanswered (the heartbeat goes on)",
    "malformed-reply": "AcousticSystems replies claim 4 bytes more payload than they carry",
    "broadcast-replies": "replies are addressed to 0xFFFF/0xFF instead of the requester",
    "from-other-system": "replies carry another system's id as their source",
    "raw-accepted": "a RAW request without a DevDataBinary ends in SENT",
    "keeps-expired-commands": "a RemoteCommand whose timeout has passed is kept for resending",
    "no-heartbeat": "the node never sends a Heartbeat (a SHOULD: caught under --strict)",
}
