"""Benchmark: what the suite costs next to the implementations it judges, every figure measured in one run.

``python -m imc_conformance.benchmark [--repeat 5] [--json FILE]`` prints medians over the repeats (these
machines are noisy: compare the ratios, measured in the same run, not absolute figures across runs), then every
target with ``met`` or ``MISSED`` and the figure measured before the start-up work beside it:

- start-up, whole processes of the package as a user installs it (run from a checkout, the benchmark builds the
  wheel and installs it into a temporary folder; the interpreter included, bytecode cached as an install has it):
  ``--version``, ``list``, ``run --adapter imcpy --message LblRange``, and the whole IMC corpus with imcpy on an
  empty cache folder (a fresh CI container);
- in-process: the whole IMC corpus through ``run_cases`` with a zero-cost adapter (answers from a table made
  beforehand with the reference codec: the runner's own cost), with imcpy, and imcpy's own calls made bare;
  the ros_acomms corpus with rosbags and genpy, and rosbags' calls made bare; each report renderer per case;
- subprocess: the whole IMC corpus through the imcpy shim, batched and one request per line, and one process per
  case (the slow anchor, sampled);
- live: the IMC scenario set against the reference node over loopback UDP, whole process, and in protocol time
  (virtual: exactly the waits a live run makes) against it and every broken node; once, the robustness phase;
- capture: ``imc-conformance pcap`` on a generated capture of a million frames, whole command, and reading alone;
- the whole protocol (issue 22): ``generate --from`` the IMC.xml imcpy ships, the ``imc-full`` folder built on
  first use, ``list`` of one of its messages, and ``run --suite imc-full --adapter imcpy`` per case beside the seed
  suite's (whole processes);
- mission logs (issue 35): ``imc-conformance log`` on an LSF log grown from DUNE's recorded log (the excerpt in
  ``tests/data/dune-log``, its frames again and again with later timestamps, judged with the IMC.xml beside it),
  uncompressed and gzip (whole command), and the peak memory of the whole command on a ~1 GB log beside a ~100 MB
  one (the logs are written into a temporary folder and removed);
- fuzzing (once each): generated messages against imcpy through hypothesis, the frame-mutation sweep against imcpy
  (beside imcpy's bare decode of such frames), the differential run of imcpy and pyimclsts (1,000 examples per
  message, whole process) and the mutants of both suites;
- the relay (once): its peak memory under a console's flood of 65,507-byte datagrams with ``--impair delay=2``
  (``relay/flood.py``);
- the reference node under a flood of HistoricSamples (``suites/imc/node/flood.py``): its slowest reply and its peak
  memory.

The rooms: ``measure`` (timing, the installed wheel, whole commands), ``targets``, one module per group of rows
(``startup``, ``inprocess``, ``programs``, ``live``, ``recordings``, ``fuzzing``, ``whole``) and ``__main__``.
"""

from __future__ import annotations

from .measure import COUNTS
from .targets import TARGETS, target_lines

__all__ = ["COUNTS", "TARGETS", "target_lines"]
