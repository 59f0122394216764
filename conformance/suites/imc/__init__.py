"""The IMC suite: LSTS's Inter-Module Communication protocol, networking messages 150–188 and acoustic
messages 200–216 (seeds 000–003), as byte vectors in both byte orders."""

from .suite import ImcSuite, load

__all__ = ["ImcSuite", "load"]
