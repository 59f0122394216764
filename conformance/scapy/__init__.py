"""A scapy layer for IMC, generated from the suite's message definitions.

``IMC`` is a frame: header fields, ``message`` (a packet of the class generated for ``mgid``), ``crc16``.
``message_class`` gives a message's class by id or abbreviation; ``to_decoded`` and ``from_decoded``
convert to and from the corpus's decoded form. Importing this package binds nothing: ``bind()`` (or
importing ``imc_conformance.scapy.bound``) makes scapy dissect UDP ports 6001–6030 and 30100–30104 as IMC.
The layer knows the IMC suite's messages; ``use_definitions(load_suite("imc-full").defs)`` gives it every
message of IMC.xml (or of any suite folder's definitions).
"""

from .binding import bind, unbind
from .decoded import from_decoded, to_decoded
from .frame import IMC, name_messages
from .messages import choose, message_class


def use_definitions(defs) -> None:
    """Dissect and build with these definitions (``Definitions`` of a suite) from now on."""
    choose(defs)
    name_messages(defs)


__all__ = ["IMC", "bind", "from_decoded", "message_class", "to_decoded", "unbind", "use_definitions"]
