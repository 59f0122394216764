"""A sample ROS 1 bag to judge: the ros_acomms corpus's realistic messages, each type as the seed edition defines it,
one a topic, written by rosbags (the `ros` extra). Usage: python sample_bag.py OUT.bag"""
import json
import sys
from pathlib import Path

from rosbags.rosbag1 import Writer

from imc_conformance.paths import VECTORS
from imc_conformance.suites import load_suite
from imc_conformance.suites.ros_acomms import codec
from imc_conformance.suites.ros_acomms.msgtext import full_text, md5

view = load_suite("ros_acomms").defs.edition("seed")
examples = json.loads((VECTORS / "ros_acomms" / "examples.json").read_text())["examples"]
writer = Writer(Path(sys.argv[1]))
writer.open()
links = {}
for i, example in enumerate(examples):
    message = example["message"]
    full = message["type"]
    if full not in links:  # one connection a type, on a topic of its own
        links[full] = writer.add_connection("/" + full.split("/")[1].lower(), full.replace("/", "/msg/"),
                                            msgdef=full_text(view, view[full]), md5sum=md5(view, view[full]))
    writer.write(links[full], 1_700_000_000 * 10**9 + i * 10**8, codec.encode(view, message))
writer.close()
