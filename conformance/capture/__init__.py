"""Captures: reading pcap and pcapng (records), finding UDP datagrams in them (datagrams), and judging what a
suite finds in those datagrams into the one result model (judge). Names no protocol: a suite brings a
``CaptureRules`` (what its frames and exchanges must be), see ``findings``."""
