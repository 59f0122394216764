"""Every mistake adapter-check can explain: what was seen, in plain words, and the fix (adapters/README.md says the
rule each fix follows). Pure: the checks that find them do the I/O. Implementation text in ``seen`` is data; the
command line escapes it like every report does."""

from __future__ import annotations

import math
from dataclasses import dataclass

README = "adapters/README.md"

# code -> (what it is, the fix). A mistake found names its code, what was seen (evidence) and where.
CATALOGUE = {
    "no-start": ("the adapter could not be started or reached",
                 "check the command (it is split like a shell would, never run by one) or the socket address"),
    "hello-late": ("no answer to hello",
                   "answer {\"id\": N, \"op\": \"hello\"} at once with one line, before anything else"),
    "unflushed": ("the hello answer came only when its input was closed: the program's output is buffered",
                  "flush stdout after every line (C: fflush(stdout) or setvbuf(stdout, NULL, _IOLBF, 0); Java: "
                  "System.out.flush(); Go: flush your bufio.Writer; Rust: stdout().flush(); Python: print(..., "
                  "flush=True))"),
    "late": ("a request was not answered within the timeout",
             "answer every request within --timeout seconds (default 5), and flush after every line"),
    "exited": ("the program ended before answering",
               "keep reading requests until the end of input (EOF), then exit 0; its stderr is shown above"),
    "no-exit": ("the program did not exit at the end of its input",
                "when stdin ends (EOF: the end of the run), answer what is in flight and exit 0; a program that "
                "waits on is killed at the end of every run, with whatever it had not yet written"),
    "not-json": ("a line on stdout is not JSON",
                 "write only answers to stdout, one JSON object per line; logs and banners go to stderr"),
    "nan-token": ("a line holds NaN or Infinity, which JSON does not have",
                  "write a NaN as \"nan\" or \"nan:<hex bits>\" and the infinities as \"inf\" and \"-inf\" (strings)"),
    "long-line": ("an answer line is longer than the suite reads (1 MB)",
                  "answer a batch whose answers would be longer one per line"),
    "not-object": ("an answer is not a JSON object",
                   "answer each request with one object {\"id\": N, \"ok\": ...}"),
    "wrong-id": ("an answer carries an id that no request in flight has",
                 "copy the request's \"id\" into its answer, unchanged (an integer)"),
    "duplicate": ("a request was answered twice", "answer every request exactly once"),
    "hello-refused": ("the hello was refused", "answer hello with \"ok\": true"),
    "hello-fields": ("the hello answer lacks what the suite needs",
                     "answer {\"id\": 1, \"ok\": true, \"implementation\": \"my-imc 2.3.0\", \"suites\": [\"imc\"], "
                     "\"byte_orders\": [\"le\", \"be\"]}: a non-empty name, the suite, the encodings it emits"),
    "hello-batch": ("the hello gives \"batch\" as something other than true or false",
                    "give \"batch\": true only if the program reads a JSON array of requests on one line"),
    "unknown-op": ("an operation the adapter does not know was not answered \"unsupported\"",
                   "answer any op you do not know {\"id\": N, \"ok\": false, \"unsupported\": true, \"error\": "
                   "\"unknown op\"} (later versions of the suite add operations)"),
    "pipelining": ("requests sent together were not all answered",
                   "read requests as they come and answer each one; the suite keeps up to 256 in flight and "
                   "never waits for an answer before sending the next request"),
    "ordering": ("an answer carries the id of another request than the one it answers",
                 "answer in any order, but each answer with the id of the request it answers (in a batch too: "
                 "never number answers by their position)"),
    "batch-unread": ("a batch (a JSON array of requests on one line) was not answered request by request",
                     "read a line that is an array as that many requests and answer each, as one array line or one "
                     "line per answer; or leave \"batch\" out of the hello"),
    "array-unasked": ("an array of answers came although the hello did not offer batches",
                      "answer one object per line, or say \"batch\": true in the hello"),
    "malformed": ("an answer is not in the form the contract gives", "see the evidence: it says what is missing"),
    "internal": ("the adapter answered \"internal\": true (its own failure)",
                 "an implementation's refusal is {\"ok\": false, \"error\": ..., \"rule\": ...}, and so is an exception "
                 "its own call throws (catch it around that call only: a NullPointerException on a null list element "
                 "is the implementation's); an accepted input is answered with what it decoded; \"internal\" only for "
                 "a bug of the adapter itself"),
    "wrong-rule": ("a refusal names a rule the input does not break",
                   "name a rule only when the check that refused is that rule's check (not because the error text "
                   "mentions a word such as CRC); omit \"rule\" when the error does not say which check failed"),
    "unknown-rule": ("a refusal names a rule the suite does not have",
                     "name one of the suite's rules (vectors/<suite>/rules.json) or none"),
    "header-absent": ("an encode request without header fields was not encoded",
                      "an absent header field means the implementation's own default: fill it with that and "
                      "encode (the suite compares only the header fields it gives)"),
    "header-missing": ("a decoded message lacks header fields",
                       "answer every header field the frame carries, with the value the implementation read"),
    "negative-zero": ("−0.0 was answered as 0",
                      "write −0.0 as -0.0 (a JSON writer that prints -0 or 0 loses the sign: JSON readers take "
                      "-0 for the integer 0); if the implementation itself drops the sign, this is its FAIL"),
    "nan-widened": ("a 32-bit float's NaN was answered with a 64-bit pattern",
                    "keep fp32 values in a 32-bit type until written and write their 8-digit bits "
                    "(\"nan:7fc00001\"); widening to a double changes the pattern and quiets a signalling NaN"),
    "nan-quieted": ("a signalling NaN was answered quieted",
                    "keep fp32 values in a 32-bit type until written: widening to a double sets the quiet bit"),
    "nan-bytes": ("a NaN's hex was written in the frame's byte order",
                  "write the bit pattern as an integer, most significant digit first (memcpy into a uint32_t and "
                  "printf(\"%08x\")), not the bytes as they are on the wire"),
    "nan-word": ("a NaN with its own bits was answered as \"nan\" (or another word)",
                 "write \"nan\" only for the default quiet NaN (7fc00000, 7ff8000000000000) and "
                 "\"nan:<hex bits>\" for any other"),
    "inf-word": ("an infinity was not answered \"inf\" or \"-inf\"",
                 "write the infinities as the strings \"inf\" and \"-inf\""),
    "float-digits": ("a float was answered with too few digits",
                     "write the shortest decimal that reads back to the same float at the field's width (Java "
                     "Float.toString/Double.toString, Go strconv.FormatFloat(v, 'g', -1, 32 or 64), Rust's {} of "
                     "an f32 or f64, C printf(\"%.9g\") for a float and \"%.17g\" for a double)"),
    "unsupported-read": ("\"unsupported\" answered for a frame of a message and byte order the adapter decodes "
                         "otherwise",
                         "\"unsupported\" says the implementation lacks the capability (it reads no frame of that "
                         "message): answer a frame it refuses {\"ok\": false, \"error\": ..., \"rule\": ...} (rule only "
                         "where its check says which), and one it reads with what it decoded"),
    "big-int": ("a large integer was answered as a float",
                "write integers as JSON integers, every digit (a writer going through a double rounds those beyond "
                "2^53: in JavaScript use a BigInt-aware writer; in Java write the long itself)"),
    "value": ("a probe was decoded with another value",
              "if the implementation reads the frame right, the adapter's conversion to the decoded form is wrong"),
}


# The fix of a mistake in the adapter's own language, where it has a habit of its own (language: see ``language``).
IN_LANGUAGE = {
    "nan-token": {
        "python": "json.dumps writes float('nan') and float('inf') as NaN and Infinity: turn each float into "
                  "\"nan\" (or \"nan:<hex bits>\"), \"inf\" or \"-inf\" before writing, and pass allow_nan=False so "
                  "that one you missed raises instead of writing a line that is not JSON",
        "java": "Gson's serializeSpecialFloatingPointValues() and Jackson's default write NaN and Infinity bare: write "
                "Float.isNaN(v) ? \"nan\" : Float.isInfinite(v) ? (v > 0 ? \"inf\" : \"-inf\") : v yourself",
        "javascript": "JSON.stringify writes NaN and Infinity as null, and hand-built lines as NaN: write \"nan\", "
                      "\"inf\" and \"-inf\" strings for them",
    },
}
LANGUAGES = {"python": ("python", ".py"), "java": ("java", ".jar", ".class", "kotlin", "gradle", "mvn"),
             "javascript": ("node", ".js", ".mjs", "deno", "bun")}


def language(argv: list[str] | None) -> str | None:
    """The language an adapter's command line names (its program or script), or None."""
    for word in (argv or [])[:3]:
        name = word.rsplit("/", 1)[-1].lower()
        for lang, marks in LANGUAGES.items():
            if any(name.startswith(m) if not m.startswith(".") else name.endswith(m) for m in marks):
                return lang
    return None


def fix_in(code: str, lang: str | None) -> str:
    """The fix of mistake ``code``, in the adapter's language where it has one of its own."""
    general = CATALOGUE[code][1]
    specific = IN_LANGUAGE.get(code, {}).get(lang or "")
    return f"{specific} ({general})" if specific else general


@dataclass(frozen=True)
class Mistake:
    code: str
    seen: str  # the evidence: what the adapter did (implementation text is data)
    where: str = ""  # the request or probe, e.g. "decode of imc/Announce/boundary/height/nan-payload"

    @property
    def what(self) -> str:
        return CATALOGUE[self.code][0]

    @property
    def fix(self) -> str:
        return CATALOGUE[self.code][1]


def value_mistake(expected, actual) -> str | None:
    """The code of a classic writer's mistake that turns ``expected`` (a decoded form's value) into ``actual``, or
    None: −0.0 as 0, an fp32 NaN widened or quieted or written in wire order, a NaN's bits lost, an infinity or a float
    with too few digits, an integer beyond 2^53 rounded through a double."""
    if isinstance(expected, float) and expected == 0 and math.copysign(1.0, expected) < 0:
        return "negative-zero" if _number(actual) and actual == 0 and math.copysign(1.0, actual) > 0 else None
    if isinstance(expected, str) and expected.startswith("nan:"):
        bits = expected[4:]
        if isinstance(actual, str) and actual.startswith("nan:"):
            got = actual[4:]
            if len(bits) == 8 and len(got) == 16:
                return "nan-widened"
            if len(bits) == len(got) == 8 and _hex(bits) is not None and _hex(got) == _hex(bits) | 0x00400000:
                return "nan-quieted"
            if len(got) == len(bits) and _hex(got) is not None and bytes.fromhex(got)[::-1].hex() == bits.lower():
                return "nan-bytes"
            return None
        return "nan-word"
    if isinstance(expected, int) and not isinstance(expected, bool) and abs(expected) >= 2 ** 53:
        return "big-int" if _number(actual) and actual != expected and abs(actual - expected) <= abs(expected) * 1e-15 \
            else None
    if expected in ("inf", "-inf"):
        return "inf-word" if actual != expected else None
    if isinstance(expected, float) and math.isfinite(expected) and _number(actual) and actual != expected:
        try:
            return "float-digits" if abs(float(actual) - expected) <= 1e-5 * abs(expected) else None
        except OverflowError:  # an integer beyond any float
            return None
    return None


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _hex(text: str) -> int | None:
    return int(text, 16) if text and all(c in "0123456789abcdefABCDEF" for c in text) else None
