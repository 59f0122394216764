"""The broken behaviours of the reference node (``serve --break NAME``): each breaks one rule a scenario
checks, so the test suite can show that the rule is caught (mutant implementations); and its variants
(``serve --variant NAME``): correct nodes that take another reading where the seeds leave one open (the ambiguity
register), which must get no FAIL."""

BREAKS = {
    "req-id-not-echoed": "AcousticStatus, IridiumTxStatus and HistoricDataQuery replies carry another req_id",
    "type-not-echoed": "AcousticStatus replies carry type MSG whatever the request's type",
    "seq-not-echoed": "SmsState replies carry another sequence number",
    "wrong-system": "AcousticOperation replies name another system than the request's",
    "status-after-terminal": "an IN_PROGRESS AcousticStatus follows the terminal status (a SHOULD: DUNE's practice)",
    "two-terminals": "AcousticStatus SENT/RANGE_RECEIVED is followed by ERROR (a SHOULD: DUNE's practice)",
    "no-terminal": "AcousticStatus stops at IN_PROGRESS (a SHOULD: DUNE's practice)",
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
    "raw-accepted": "a RAW request without a DevDataBinary ends in SENT (a SHOULD: the seed gives no status a meaning)",
    "keeps-expired-commands": "a RemoteCommand whose timeout has passed is kept for resending",
    "no-heartbeat": "the node never sends a Heartbeat (a SHOULD: caught under --strict)",
    "silent-on-unsupported": "an AcousticOperation with an operation code it does not know goes unanswered (a SHOULD)",
    "ignores-timeout": "an AcousticRequest's status ends long after the request's timeout (a SHOULD)",
    "ignores-max-size": "a QUERY's reply carries all the kept data, whatever max_size says (a SHOULD)",
    "transmits-logged-samples": "historic samples of priority -127 are kept for transmission",
    "transmits-in-arrival-order": "historic samples are transmitted in the order they came, whatever their priority",
    "ignores-remote-commands": "a RemoteCommand addressed to the node is not executed (a SHOULD)",
    "acknowledges-set-cfg": "SET_CFG is answered with a CUR_CFG (a SHOULD: deployed nodes store it silently)",
    "merges-set-cfg": "a second SET_CFG adds its beacons to the stored ones instead of replacing them",
    "stores-cur-cfg": "a CUR_CFG it receives replaces the stored beacons (a SHOULD)",
    "stops-after-unknown-op": "after an LblConfig with an operation it does not know, LblConfig goes unanswered",
    "acks-unreachable": "an ABORT to a system not on the acoustic channel ends in ABORT_ACKED",
    "transmits-after-ttl": "an Iridium message is transmitted (TRANSMIT) 2 s after its time to live has passed",
    "replies-to-first-client": "every reply goes to the first system that announced itself, whoever asked",
    "never-forwards": "a RemoteCommand for another system on the link is kept, never resent to it (a SHOULD)",
    "resends-expired": "a stored RemoteCommand whose timeout passes while it is stored is still handed out",
    "leaks-on-drop": "after 5,000 datagrams it could not decode, no request is served (caught by --robustness)",
}

VARIANTS = {
    "sent-before-range-received": "RANGE and REVERSE_RANGE AcousticRequests report SENT before RANGE_RECEIVED (as DUNE)",
    "busy-then-completes": "a request that finds the modem busy is answered BUSY, then carried out once the modem is free",
    "queued-first": "AcousticStatus starts at QUEUED and AcousticOperation MSG at MSG_QUEUED",
    "silent-where-allowed": "no report for AcousticOperation MSG_SHORT, REVERSE_RANGE and MSG without a message (as DUNE)",
    "old-unsupported-code": "AcousticStatus UNSUPPORTED is sent as 154 (as DUNE before 2024-10)",
    "slow-announce": "announces only every 60 s, not at first contact",
    "msg-to-unreachable-done": "a MSG to a system not on the acoustic channel ends in MSG_DONE (sent, no acknowledgement)",
}
