"""ROS 1 definition texts: .msg and .srv files, the MD5 of a type, its full definition text, and reading such
texts back (an implementation's description of a type, or a team's own .msg files).

The MD5 is taken over a canonical text: constants first as ``type NAME=value``, then one line per field,
``type name`` for builtins (array suffix kept) and ``<md5 of the type> name`` for nested message types
(array suffix dropped), lines joined by newlines. A service's MD5 is that of its request's canonical text
followed directly by its response's. The full text is the type's .msg text followed, for each type it
nests (depth first, each once), by a line of 80 ``=``, ``MSG: <type>`` and that type's text.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass

from .definitions import PRIMITIVES, DefinitionError, Edition, FieldType, Message, parse_type

SEPARATOR = "=" * 80
FIELD_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


def msg_text(message: Message) -> str:
    """The type's .msg text: constants, then fields, one per line, no comments."""
    package = message.definition.package
    lines = [f"{c.type} {c.name}={c.value}" for c in message.definition.constants]
    lines += [f"{f.type.text(package)} {f.name}" for f in message.fields]
    return "\n".join(lines) + "\n"


def canonical_text(edition: Edition, message: Message) -> str:
    return _canonical(((c.type, c.name, c.value) for c in message.definition.constants),
                      ((f.type, f.name) for f in message.fields), lambda base: md5(edition, edition[base]))


def _canonical(constants, fields, md5_of) -> str:
    """The text a type's MD5 is taken over: ``constants`` (type, name, value), then ``fields`` (FieldType, name),
    a nested type's field by ``md5_of(its type)``."""
    lines = [f"{t} {name}={value}" for t, name, value in constants]
    lines += [f"{t.text('')} {name}" if t.is_builtin else f"{md5_of(t.base)} {name}" for t, name in fields]
    return "\n".join(lines)


def md5(edition: Edition, message: Message) -> str:
    return hashlib.md5(canonical_text(edition, message).encode("utf-8")).hexdigest()


def service_md5(edition: Edition, request: Message, response: Message) -> str:
    text = canonical_text(edition, request) + canonical_text(edition, response)
    return hashlib.md5(text.encode("utf-8")).hexdigest()


def full_text(edition: Edition, message: Message) -> str:
    """The type's text followed by the text of every type it nests (what a ROS 1 connection header carries)."""
    parts = [msg_text(message)]
    for dep in edition.dependencies(message):
        parts.append(f"{SEPARATOR}\nMSG: {dep.full}\n{msg_text(dep)}")
    return "\n".join(parts)


# ---------------------------------------------------------------- reading definition texts

@dataclass(frozen=True)
class ParsedType:
    """A type as a definition text gives it: constants as (type, name, value), fields as (type, name)."""

    constants: tuple[tuple[str, str, str], ...]
    fields: tuple[tuple[FieldType, str], ...]


def parse_msg(text: str, package: str, where: str = "") -> ParsedType:
    """The constants and fields of one .msg text (comments and blank lines ignored); DefinitionError names the
    line of a syntax error."""
    constants, fields = [], []
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        at = f"{where}line {number}: " if where else f"line {number}: "
        if line.startswith("string ") and "=" in line:  # a string constant keeps everything after '='
            name, value = line[len("string "):].split("=", 1)
            constants.append(("string", name.strip(), value))
            continue
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split(None, 1)
        if len(parts) != 2:
            raise DefinitionError(f"{at}{raw.strip()!r} is not 'type name' or 'type NAME=value'")
        type_text, rest = parts
        if "=" in rest:
            name, value = (x.strip() for x in rest.split("=", 1))
            if type_text not in PRIMITIVES or not FIELD_NAME.match(name):
                raise DefinitionError(f"{at}{raw.strip()!r} is not a constant of a primitive type")
            constants.append((type_text, name, value))
            continue
        if not FIELD_NAME.match(rest):
            raise DefinitionError(f"{at}{rest!r} is not a field name")
        try:
            fields.append((parse_type(type_text, package), rest))
        except DefinitionError as exc:
            raise DefinitionError(f"{at}{exc}") from None
    return ParsedType(tuple(constants), tuple(fields))


def parse_full_text(text: str, full: str) -> dict[str, ParsedType]:
    """Every type a full definition text describes, by full name (the first section is ``full``)."""
    sections = re.split(rf"\n?{SEPARATOR}\n", text)
    out = {full: parse_msg(sections[0], full.split("/")[0])}
    for section in sections[1:]:
        head, _, body = section.partition("\n")
        if not head.startswith("MSG: "):
            raise DefinitionError(f"a section of the definition starts {head[:60]!r}, not 'MSG: <type>'")
        name = parse_type(head[len("MSG: "):], "").base
        if "/" not in name:
            raise DefinitionError(f"section type {name!r} is not a package/Name")
        out[name] = parse_msg(body, name.split("/")[0])
    return out


def text_md5(types: dict[str, ParsedType], full: str) -> str:
    """The MD5 of type ``full`` as a definition text describes it (``parse_full_text``: it and every type it nests);
    DefinitionError where it nests a type the text lacks, or itself. Iterative: the text is untrusted input."""
    done: dict[str, str] = {}
    stack, begun = [full], set()
    while stack:
        name = stack[-1]
        if name in done:
            stack.pop()
            continue
        parsed = types.get(name)
        if parsed is None:
            raise DefinitionError(f"the definition lacks {name}, which {full if name != full else 'it'} nests")
        missing = [t.base for t, _ in parsed.fields if not t.is_builtin and t.base not in done]
        if missing:
            if name in begun:
                raise DefinitionError(f"{name} nests itself")
            begun.add(name)
            stack += missing
            continue
        done[name] = hashlib.md5(_canonical(parsed.constants, parsed.fields, done.__getitem__).encode("utf-8")).hexdigest()
        stack.pop()
    return done[full]


def expected_types(edition: Edition, message: Message) -> dict[str, ParsedType]:
    """What a correct full text of ``message`` describes."""
    return {m.full: ParsedType(tuple((c.type, c.name, c.value) for c in m.definition.constants),
                               tuple((f.type, f.name) for f in m.fields))
            for m in (message, *edition.dependencies(message))}


def text_differences(expected: dict[str, ParsedType], actual: dict[str, ParsedType]) -> list[str]:
    """How an answered definition differs from the expected one, type by type, field by field."""
    out = []
    for name in [n for n in expected if n not in actual]:
        out.append(f"the definition lacks {name}")
    for name in [n for n in actual if n not in expected]:
        out.append(f"the definition describes {name}, which the type does not nest")
    for name, want in expected.items():
        got = actual.get(name)
        if got is None:
            continue
        if {(t, n, _number(v)) for t, n, v in got.constants} != {(t, n, _number(v)) for t, n, v in want.constants}:
            out.append(f"{name}: constants {_show_constants(got.constants)}, expected {_show_constants(want.constants)}")
        for i in range(max(len(want.fields), len(got.fields))):
            w = want.fields[i] if i < len(want.fields) else None
            g = got.fields[i] if i < len(got.fields) else None
            if w != g:
                out.append(f"{name}: field {i + 1} is {_show_field(g)}, expected {_show_field(w)}")
    return out


def _number(value: str):
    try:
        return int(value, 0)
    except ValueError:
        return value.strip()


def _show_field(field) -> str:
    return "missing" if field is None else f"'{field[0].text('')} {field[1]}'"


def _show_constants(constants) -> str:
    return "[" + ", ".join(f"{t} {n}={v}" for t, n, v in constants) + "]"
