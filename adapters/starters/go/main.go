// A starter adapter for imc-conformance (ADAPTER-CONTRACT.md): the protocol loop, answering every request "unsupported"
// until the TODOs call your implementation, and the decoded form's values done right (floats by their bits at the
// field's width: -0.0, NaN payloads, fp32 kept 32-bit; hex). With --values it reads value probes instead (what the
// suite's tests check the helpers with). Build: go build -o starter .
package main

import (
	"bufio"
	"encoding/hex"
	"encoding/json"
	"fmt"
	"math"
	"os"
	"strconv"
	"strings"
)

var defaultNaN = map[int]uint64{4: 0x7fc00000, 8: 0x7ff8000000000000}

func main() {
	in := bufio.NewReader(os.Stdin)
	out := bufio.NewWriter(os.Stdout) // flushed after every line
	values := len(os.Args) > 1 && os.Args[1] == "--values"
	for {
		line, err := in.ReadBytes('\n') // lines of any length
		if len(strings.TrimSpace(string(line))) > 0 {
			decoder := json.NewDecoder(strings.NewReader(string(line)))
			decoder.UseNumber() // numbers keep their text: an fp32 is parsed at 32 bits
			var request map[string]any
			var reply any
			if decodeErr := decoder.Decode(&request); decodeErr != nil {
				reply = map[string]any{"id": nil, "ok": false, "internal": true, "error": decodeErr.Error()}
			} else if values {
				reply = valueProbe(request)
			} else {
				reply = answer(request)
			}
			text, _ := json.Marshal(reply)
			out.Write(append(text, '\n'))
			out.Flush()
		}
		if err != nil {
			return // end of input: the end of the run
		}
	}
}

func answer(request map[string]any) map[string]any {
	reply := map[string]any{"id": request["id"]}
	switch request["op"] {
	case "hello":
		reply["ok"] = true
		reply["implementation"] = "my-imc 0.0.0 (starter: nothing implemented yet)" // TODO: name and version
		reply["suites"] = []string{"imc"}
		reply["byte_orders"] = []string{"le", "be"} // TODO: the byte orders your implementation emits
		return reply
	case "encode":
		// TODO: build your message from request["message"] (read floats with floatBits(value, 4 or 8)), serialize it
		// in request["byte_order"], and answer reply["ok"] = true, reply["frame"] = hex.EncodeToString(frame).
		// What the implementation's own call returns or panics with is its answer, not the adapter's bug:
		//   frame, err := codec.Marshal(msg); if err != nil { return refuse(reply, err.Error(), "") }
		// and a panic inside it (a nil element of a list) is recovered around that call only and refused the same way.
		return unsupported(reply, "encode is not implemented yet")
	case "decode":
		// TODO: frame, err := hex.DecodeString(request["frame"].(string)); deserialize it; answer its abbrev, the five
		// header fields and every field (floats with floatJSON(bits, 4 or 8)). A refusal: refuse(reply, error, rule),
		// with a rule only when the check that refused is that rule's check.
		return unsupported(reply, "decode is not implemented yet")
	}
	return unsupported(reply, "unknown op")
}

func unsupported(reply map[string]any, why string) map[string]any {
	reply["ok"], reply["unsupported"], reply["error"] = false, true, why
	return reply
}

func refuse(reply map[string]any, error string, rule string) map[string]any {
	reply["ok"], reply["error"] = false, error
	if rule != "" {
		reply["rule"] = rule
	}
	return reply
}

// floatJSON is the decoded form of the float of width bytes with these IEEE bits: a number (-0.0 keeps its sign, an
// fp32 written with its own shortest digits), "inf", "-inf", "nan" (the default quiet NaN) or "nan:<hex bits>".
// encoding/json would write -0.0 as -0 (read back as the integer 0) and refuses NaN: the text is made here.
func floatJSON(bits uint64, width int) json.RawMessage {
	var x float64
	if width == 4 {
		f := math.Float32frombits(uint32(bits))
		if f != f {
			return nanJSON(bits, width)
		}
		x = float64(f)
	} else {
		x = math.Float64frombits(bits)
		if x != x {
			return nanJSON(bits, width)
		}
	}
	if math.IsInf(x, 0) {
		if x > 0 {
			return json.RawMessage(`"inf"`)
		}
		return json.RawMessage(`"-inf"`)
	}
	text := strconv.FormatFloat(x, 'g', -1, width*8) // the shortest digits that read back at this width
	if !strings.ContainsAny(text, ".eEn") {
		text += ".0" // a float, never an integer: -0 becomes -0.0
	}
	return json.RawMessage(text)
}

func nanJSON(bits uint64, width int) json.RawMessage {
	if bits == defaultNaN[width] {
		return json.RawMessage(`"nan"`)
	}
	return json.RawMessage(fmt.Sprintf(`"nan:%0*x"`, width*2, bits))
}

// floatBits reads a decoded form's float (a json.Number, or "inf", "-inf", "nan", "nan:<hex>") as its bits at width.
func floatBits(value any, width int) (uint64, error) {
	switch v := value.(type) {
	case json.Number:
		x, err := strconv.ParseFloat(string(v), width*8) // parsed once, at the field's width
		if err != nil {
			return 0, err
		}
		if width == 4 {
			return uint64(math.Float32bits(float32(x))), nil
		}
		return math.Float64bits(x), nil
	case string:
		switch {
		case v == "nan":
			return defaultNaN[width], nil
		case strings.HasPrefix(v, "nan:"):
			return strconv.ParseUint(v[4:], 16, width*8)
		case v == "inf" || v == "-inf":
			sign := 1
			if v == "-inf" {
				sign = -1
			}
			if width == 4 {
				return uint64(math.Float32bits(float32(math.Inf(sign)))), nil
			}
			return math.Float64bits(math.Inf(sign)), nil
		}
	}
	return 0, fmt.Errorf("not a float: %v", value)
}

// valueProbe: {"width": 4|8, "bits": hex} -> the value written and the bits read back; {"hex": ...} -> it, read and
// written again.
func valueProbe(probe map[string]any) map[string]any {
	if text, ok := probe["hex"].(string); ok {
		raw, err := hex.DecodeString(text)
		if err != nil {
			return map[string]any{"error": err.Error()}
		}
		return map[string]any{"hex": hex.EncodeToString(raw)}
	}
	width, _ := strconv.Atoi(string(probe["width"].(json.Number)))
	bits, _ := strconv.ParseUint(probe["bits"].(string), 16, 64)
	value := floatJSON(bits, width)
	decoder := json.NewDecoder(strings.NewReader(string(value)))
	decoder.UseNumber()
	var reread any
	decoder.Decode(&reread)
	back, err := floatBits(reread, width)
	if err != nil {
		return map[string]any{"value": value, "error": err.Error()}
	}
	return map[string]any{"value": value, "bits": fmt.Sprintf("%0*x", width*2, back)}
}
