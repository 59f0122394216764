"""The whole protocol's definitions of messages a selected suite lacks, for judging traffic: an inline message of a
vehicle's other traffic (a HistoricSample holding an EstimatedState, as a DUNE vehicle's data store sends) is read
with the IMC.xml imcpy ships, if the cache holds it. Never fetched here: judging traffic neither waits on the network
nor fails without it."""

from __future__ import annotations

from ...cache import cache_dir
from ...inputs import read_bytes
from ...limits import XML_LIMIT
from .definitions import Definitions, MessageDef, parse_definitions
from .from_xml import XmlError, xml_document
from .imc_xml import cached_imc_xml


def defined_elsewhere(mgid: int) -> MessageDef | str:
    """The whole IMC.xml's definition of message ``mgid`` (an inline message the selected suite lacks: a vehicle's
    HistoricSample holding an EstimatedState), or why there is none: no definition names the id, or the IMC.xml is
    not in the cache (never fetched here: see ``imc_xml.cached_imc_xml``)."""
    try:
        whole = _cached_whole(str(cache_dir()))
    except OSError as exc:
        whole = f"no cache folder: {exc}"
    if isinstance(whole, str):
        return whole
    mdef = whole.by_id.get(mgid)
    return mdef if mdef is not None else f"no IMC.xml the suite has defines message id {mgid}"


_READ: dict[str, Definitions] = {}  # cache folder -> the definitions of the IMC.xml it holds


def _cached_whole(root: str) -> Definitions | str:
    """The cached IMC.xml's definitions (read once per cache folder, once it holds the file: a fetch made later, by
    ``--suite imc-full`` or another run, is seen), or why they cannot be had."""
    if root in _READ:
        return _READ[root]
    path = cached_imc_xml()
    if path is None:
        return "the whole IMC.xml is not in the cache (`--suite imc-full` fetches it)"
    try:
        _READ[root] = parse_definitions(xml_document(read_bytes(path, XML_LIMIT)))
    except (XmlError, ValueError, LookupError, TypeError) as exc:
        return f"the cached IMC.xml cannot be read: {exc}"
    return _READ[root]
