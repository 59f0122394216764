"""A vehicle's LSF log holding three systems' frames, each stamped by its own clock: the vehicle's (id 30), a ground
station's running 42 s late (system 19696) and a peer vehicle's running 12 s early (31), in the order they came, with the
station's acoustic and Iridium requests, the peer's queries and the vehicle's replies. Usage: python skewed_log.py
OUT.lsf [FRAMES]"""
import sys

from imc_conformance.suites import load_suite
from imc_conformance.suites.imc.traffic import PEER, STATION, write_log

suite = load_suite("imc")
frames = int(sys.argv[2]) if len(sys.argv) > 2 else 3000
write_log(sys.argv[1], suite.defs, suite.wire, suite.editions[0], frames, clocks={STATION: -42.0, PEER: 12.0})
