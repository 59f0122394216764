"""Mutant IMC implementations: the reference codec with one seeded bug each.

"A suite that never fails proves nothing": tests/test_mutants.py runs every mutant over the corpus and
shows which cases catch its bug. ``Reference`` wraps the reference codec as a library adapter;
``Stepwise`` rebuilds its decoder from the codec's pieces, one method per check in DUNE's order, so
that a mutant overrides exactly the check or the reading it gets wrong. Each mutant's docstring is
its bug. Every mutant is importable from here by its class name (an adapter file may name one).

The rooms: ``base`` (the two baselines and the buggy encoders' helpers), ``rules`` (one rule switched off each, one
wrong rule), ``seeded`` (the first set of encoding and value bugs), ``fuzzed`` (the set added with the fuzzer,
``NEW``), ``unseen`` (readers nobody here wrote, ``UNSEEN``) and ``permitted`` (choices that must survive).
"""

from __future__ import annotations

from .base import MIN_NORMAL, Reference, Stepwise
from .fuzzed import (BitfieldDropsTopBit, CrcAlwaysBigEndian, CrcCcitt, CrcOverPayloadOnly, DropsFifthListElement,
                     DstIgnoredOnEncode, EmptyListAsNullCount, EntitiesSwapped, Fp32AsFp64, Fp64ConditionalBug,
                     Int8MinAsPositive, Int16AsUint16, Int16MinSaturates, LastEnumValueOffByOne, ListCountU8,
                     ListElementsReversed, NanCanonicalOnEncode, NegativeZeroTimestampLost, NestedInlineIsNull,
                     NullInlineAsZero, PlaintextCutAt255, RawdataLosesLastOddByte, RejectsBigEndian, SizeCountsFooter,
                     SizeCountsHeader, SizeLimitOffByOne, SyncFirstByteOnly, TimestampLittleEndianAlways,
                     TrimsTrailingSpaces, Uint8Saturates, Uint32ReadSigned)
from .permitted import LittleEndianOnly, RefusesTrailingBytes
from .rules import (PER_RULE, BlamesCrc, CrcUnchecked, FieldOverrunUnchecked, HeaderTruncatedUnchecked,
                    LengthOverrunUnchecked, ListCountOverrunUnchecked, PayloadOverflowUnchecked,
                    SizeExceedsDataUnchecked, SyncUnchecked, UnknownIdUnchecked, UnknownInlineIdUnchecked)
from .seeded import (BePayloadLittleEndian, CanonicalNan, CrcLittleEndianInBe, CrcModbus, DropsNegativeZero,
                     FlushesSubnormals, IgnoresTimestamp, ListCountMinusOne, PlaintextLengthPlusOne,
                     PlaintextStopsAtNul, RssiValueAsFp64, SignedSrc)
from .unseen import (SENDING_TIME, CrashesOnNullElement, CrcAtEndOfData, HoldsSizeLimit, IgnoresSize,
                     RestampsTimestamps, RestampsZeroTimestamps)

MUTANTS = (
    *PER_RULE, BlamesCrc,
    CrcLittleEndianInBe, CrcModbus, BePayloadLittleEndian, DropsNegativeZero, FlushesSubnormals, CanonicalNan,
    PlaintextStopsAtNul, PlaintextLengthPlusOne, ListCountMinusOne, RssiValueAsFp64, SignedSrc, IgnoresTimestamp,
    RefusesTrailingBytes, LittleEndianOnly,
    CrcOverPayloadOnly, CrcCcitt, CrcAlwaysBigEndian, SizeCountsHeader, SizeCountsFooter, ListCountU8, NullInlineAsZero,
    SyncFirstByteOnly, RejectsBigEndian, SizeLimitOffByOne, TimestampLittleEndianAlways, EntitiesSwapped,
    DstIgnoredOnEncode, Fp32AsFp64, Int16AsUint16, Uint32ReadSigned, Int16MinSaturates, Uint8Saturates, Fp64ConditionalBug,
    DropsFifthListElement, TrimsTrailingSpaces, RawdataLosesLastOddByte, BitfieldDropsTopBit, LastEnumValueOffByOne,
    NestedInlineIsNull, EmptyListAsNullCount, PlaintextCutAt255, NanCanonicalOnEncode, NegativeZeroTimestampLost,
    Int8MinAsPositive, ListElementsReversed,
    IgnoresSize, CrcAtEndOfData, RestampsTimestamps, RestampsZeroTimestamps, CrashesOnNullElement, HoldsSizeLimit,
)
NEW = MUTANTS[MUTANTS.index(CrcOverPayloadOnly):MUTANTS.index(IgnoresSize)]  # added with the fuzzer
UNSEEN = MUTANTS[MUTANTS.index(IgnoresSize):]  # readers nobody here wrote: each caught by the corpus itself

__all__ = ["MIN_NORMAL", "SENDING_TIME", "Reference", "Stepwise", "PER_RULE", "MUTANTS", "NEW", "UNSEEN",
           *(m.__name__ for m in MUTANTS)]
