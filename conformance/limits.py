"""Every bound on what a user, an implementation, a node or a capture may give the suite, in one place: the
command line refuses what the readers would refuse (a run records only what ``pcap`` reads back), and every
reader of untrusted input stops at its bound with a one-line reason."""

from __future__ import annotations

from .core.bounds import SHARDS_MAX  # shards a selection may be split into (--shard K/N), as a saved result may say

STARTUP_MAX = 3600.0  # seconds a live run waits for its target to show itself
TIME_SCALE_MAX = 1000.0  # the factor on a live run's time bounds (--time-scale)
TIMEOUT_MAX = 86_400.0  # seconds an adapter may take over one request (--timeout)
MEMORY_LIMIT_MAX = 1 << 20  # megabytes of data memory an adapter process may be given (--memory-limit; 0: none)
UNIQUE_SPAN = 0xFFF0  # a live run's unique numbers (request ids) cycle through 1..UNIQUE_SPAN
FILE_LIMIT = 256 << 20  # bytes of a JSON or text file the suite reads (claims, waivers, results, corpus files)
PIPE_LIMIT = 1 << 30  # bytes of a capture read from a pipe or a device
NESTING_LIMIT = 64  # inline messages within inline messages that a decoder follows (the corpus needs 4)
XML_LIMIT = 16 << 20  # bytes of an IMC.xml (IMC.xml 5.4.30 is 0.6 MB)
JSON_NESTING_LIMIT = 200  # arrays and objects within each other in JSON from outside (64 inline messages need ~130)
# What generate builds from an IMC.xml: a message's weight is its fields times the values one of its cases carries
# (its corpus grows as that product), a corpus's is the sum of its messages' and 64 for each (the framing cases).
MESSAGE_WEIGHT_MAX = 4096  # IMC.xml 5.4.30's heaviest message weighs 779; 64 scalar fields weigh 4,096
CORPUS_WEIGHT_MAX = 131_072  # IMC.xml 5.4.30 weighs 36,896 (338 messages)
GENERATED_LIMIT = 1 << 30  # bytes of case files written (IMC.xml 5.4.30's: 147 MB)
FUZZ_COUNT_MAX = 1_000_000  # examples (--budget) or mutations (--sweep) per message a fuzzing run may be asked for
