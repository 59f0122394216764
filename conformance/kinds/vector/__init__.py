"""The byte-vector case kind: a frame and/or a message with the verdict a conforming implementation reaches."""

from .kind import Span, VectorCodec, VectorKind

__all__ = ["Span", "VectorCodec", "VectorKind"]
