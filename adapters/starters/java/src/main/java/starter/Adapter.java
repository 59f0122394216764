package starter;

import com.fasterxml.jackson.databind.JsonNode;
import com.fasterxml.jackson.databind.ObjectMapper;
import com.fasterxml.jackson.databind.node.JsonNodeFactory;
import com.fasterxml.jackson.databind.node.ObjectNode;

import java.io.BufferedReader;
import java.io.IOException;
import java.io.InputStreamReader;
import java.io.PrintStream;
import java.nio.charset.StandardCharsets;
import java.util.HexFormat;

/**
 * A starter adapter for imc-conformance (ADAPTER-CONTRACT.md): the protocol loop, answering every request
 * "unsupported" until the TODOs call your implementation, and the decoded form's values done right (floats by their
 * bits at the field's width: -0.0, NaN payloads, fp32 kept 32-bit; hex). {@code --values} reads value probes instead
 * (what the suite's tests check the helpers with).
 */
public final class Adapter {
    static final ObjectMapper JSON = new ObjectMapper();
    static final JsonNodeFactory NODES = JsonNodeFactory.instance;
    static final long[] DEFAULT_NAN = {0, 0, 0, 0, 0x7fc00000L, 0, 0, 0, 0x7ff8000000000000L};

    public static void main(String[] args) throws IOException {
        // Answers only on stdout, each line flushed; anything else (logs) goes to stderr.
        PrintStream out = new PrintStream(new java.io.FileOutputStream(java.io.FileDescriptor.out), false, StandardCharsets.UTF_8);
        System.setOut(System.err);
        BufferedReader in = new BufferedReader(new InputStreamReader(System.in, StandardCharsets.UTF_8));
        boolean values = args.length > 0 && args[0].equals("--values");
        for (String line; (line = in.readLine()) != null; ) {  // lines of any length
            if (line.isBlank()) continue;
            JsonNode request = JSON.readTree(line);
            out.println(JSON.writeValueAsString(values ? valueProbe(request) : answer(request)));
            out.flush();
        }
    }

    static ObjectNode answer(JsonNode request) {
        ObjectNode reply = NODES.objectNode();
        reply.set("id", request.get("id"));
        String op = request.path("op").asText();
        try {
            switch (op) {
                case "hello":
                    reply.put("ok", true);
                    reply.put("implementation", "my-imc 0.0.0 (starter: nothing implemented yet)");  // TODO: name and version
                    reply.putArray("suites").add("imc");
                    reply.putArray("byte_orders").add("le").add("be");  // TODO: the byte orders your implementation emits
                    return reply;
                case "encode":
                    // TODO: build your message from request.get("message") (read floats with floatBits(node, 4 or 8)),
                    // serialize it in request.get("byte_order"), and answer reply.put("frame", toHex(bytes)).
                    // An exception thrown by the implementation's own call is its answer, not the adapter's bug:
                    //   try { bytes = codec.serialize(msg); }
                    //   catch (RuntimeException e) { return refuse(reply, e.toString(), null); }  // e.g. an NPE on a null list element
                    return unsupported(reply, "encode is not implemented yet");
                case "decode":
                    // TODO: byte[] frame = fromHex(request.get("frame").asText()); deserialize it; answer its abbrev, the
                    // five header fields and every field (floats with floatJson(bits, 4 or 8)). A refusal:
                    // refuse(reply, error, rule) with a rule only when the check that refused is that rule's check; an
                    // exception the implementation's deserialize throws (IndexOutOfBounds on a short frame) is a
                    // refusal without a rule: catch it around that call only, as for encode.
                    return unsupported(reply, "decode is not implemented yet");
                default:
                    return unsupported(reply, "unknown op");
            }
        } catch (RuntimeException e) {  // a bug of the adapter's own code (reading the request, writing the answer)
            reply.removeAll();
            reply.set("id", request.get("id"));
            reply.put("ok", false).put("internal", true).put("error", e.toString());
            return reply;
        }
    }

    static ObjectNode unsupported(ObjectNode reply, String why) {
        return reply.put("ok", false).put("unsupported", true).put("error", why);
    }

    static ObjectNode refuse(ObjectNode reply, String error, String rule) {
        reply.put("ok", false).put("error", error);
        return rule == null ? reply : reply.put("rule", rule);
    }

    /** The decoded form of the float of {@code width} bytes with these IEEE bits: a number (-0.0 keeps its sign; an
     * fp32 is written as a float, never widened), "inf", "-inf", "nan" (the default quiet NaN) or "nan:&lt;hex bits&gt;". */
    static JsonNode floatJson(long bits, int width) {
        if (width == 4) {
            float f = Float.intBitsToFloat((int) bits);
            if (Float.isNaN(f)) return nanJson(bits & 0xffffffffL, 4);
            if (Float.isInfinite(f)) return NODES.textNode(f > 0 ? "inf" : "-inf");
            return NODES.numberNode(f);  // Float.toString: the fp32's own digits, "-0.0" for -0.0
        }
        double d = Double.longBitsToDouble(bits);
        if (Double.isNaN(d)) return nanJson(bits, 8);
        if (Double.isInfinite(d)) return NODES.textNode(d > 0 ? "inf" : "-inf");
        return NODES.numberNode(d);
    }

    static JsonNode nanJson(long bits, int width) {
        if (bits == DEFAULT_NAN[width]) return NODES.textNode("nan");
        return NODES.textNode(width == 4 ? String.format("nan:%08x", bits) : String.format("nan:%016x", bits));
    }

    /** The IEEE bits (at {@code width} bytes) of a decoded form's float: a number, "inf", "-inf", "nan", "nan:&lt;hex&gt;". */
    static long floatBits(JsonNode value, int width) {
        if (value.isTextual()) {
            String text = value.asText();
            if (text.equals("nan")) return DEFAULT_NAN[width];
            if (text.startsWith("nan:")) return Long.parseUnsignedLong(text.substring(4), 16);
            if (text.equals("inf") || text.equals("-inf")) {
                boolean negative = text.startsWith("-");
                return width == 4 ? Float.floatToRawIntBits(negative ? Float.NEGATIVE_INFINITY : Float.POSITIVE_INFINITY) & 0xffffffffL
                        : Double.doubleToRawLongBits(negative ? Double.NEGATIVE_INFINITY : Double.POSITIVE_INFINITY);
            }
            throw new IllegalArgumentException("not a float: " + text);
        }
        // Jackson reads a number as a double (-0.0 keeps its sign); an fp32 field's shortest decimal, as the suite writes
        // it, rounds to the same float through the double
        double d = value.doubleValue();
        return width == 4 ? Float.floatToRawIntBits((float) d) & 0xffffffffL : Double.doubleToRawLongBits(d);
    }

    static String toHex(byte[] bytes) { return HexFormat.of().formatHex(bytes); }  // lowercase, two digits a byte

    static byte[] fromHex(String hex) { return HexFormat.of().parseHex(hex.toLowerCase()); }

    /** {"width": 4|8, "bits": hex} -> the value written and the bits read back; {"hex": ...} -> it, read and written. */
    static ObjectNode valueProbe(JsonNode probe) {
        ObjectNode reply = NODES.objectNode();
        if (probe.has("hex")) return reply.put("hex", toHex(fromHex(probe.get("hex").asText())));
        int width = probe.get("width").asInt();
        JsonNode value = floatJson(Long.parseUnsignedLong(probe.get("bits").asText(), 16), width);
        reply.set("value", value);
        try {
            JsonNode reread = JSON.readTree(JSON.writeValueAsString(value));
            return reply.put("bits", String.format(width == 4 ? "%08x" : "%016x", floatBits(reread, width)));
        } catch (IOException e) {
            throw new IllegalStateException(e);
        }
    }
}
