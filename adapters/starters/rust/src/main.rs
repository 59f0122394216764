//! A starter adapter for imc-conformance (ADAPTER-CONTRACT.md): the protocol loop, answering every request "unsupported"
//! until the TODOs call your implementation, and the decoded form's values done right (floats by their bits at the
//! field's width: -0.0, NaN payloads, fp32 kept 32-bit; hex). With --values it reads value probes instead (what the
//! suite's tests check the helpers with). Build: cargo build --release.

use serde_json::{json, Map, Value};
use std::io::{self, BufRead, Write};

fn main() {
    let values = std::env::args().nth(1).as_deref() == Some("--values");
    let stdin = io::stdin();
    let mut out = io::stdout().lock();
    for line in stdin.lock().lines() {
        // lines of any length; the end of input is the end of the run
        let Ok(line) = line else { break };
        if line.trim().is_empty() {
            continue;
        }
        let reply = match serde_json::from_str::<Value>(&line) {
            Ok(request) if values => value_probe(&request),
            Ok(request) => answer(&request),
            Err(e) => json!({"id": null, "ok": false, "internal": true, "error": e.to_string()}),
        };
        let _ = writeln!(out, "{reply}");
        let _ = out.flush(); // every line, at once
    }
}

fn answer(request: &Value) -> Value {
    let id = request.get("id").cloned().unwrap_or(Value::Null);
    match request.get("op").and_then(Value::as_str) {
        Some("hello") => json!({
            "id": id, "ok": true,
            "implementation": "my-imc 0.0.0 (starter: nothing implemented yet)", // TODO: name and version
            "suites": ["imc"],
            "byte_orders": ["le", "be"], // TODO: the byte orders your implementation emits
        }),
        // TODO: build your message from request["message"] (read floats with float_bits(value, 4 or 8)), serialize it
        // in request["byte_order"], and answer {"id": id, "ok": true, "frame": to_hex(&frame)}.
        // The implementation's own Err is its answer, not the adapter's bug:
        //   match codec::encode(&msg) { Ok(frame) => ..., Err(e) => refuse(id, &e.to_string(), None) }
        // (a panic inside its call, e.g. an index out of bounds, may be caught with std::panic::catch_unwind around
        // that call only and refused the same way; left uncaught it ends the program: a CRASH of that case).
        Some("encode") => unsupported(id, "encode is not implemented yet"),
        // TODO: let frame = from_hex(request["frame"].as_str()...); deserialize it; answer its abbrev, the five header
        // fields and every field (floats with float_json(bits, 4 or 8)). A refusal: refuse(id, error, rule), with a rule
        // only when the check that refused is that rule's check.
        Some("decode") => unsupported(id, "decode is not implemented yet"),
        _ => unsupported(id, "unknown op"),
    }
}

fn unsupported(id: Value, why: &str) -> Value {
    json!({"id": id, "ok": false, "unsupported": true, "error": why})
}

#[allow(dead_code)] // TODO: used by your decode and encode
fn refuse(id: Value, error: &str, rule: Option<&str>) -> Value {
    let mut reply = json!({"id": id, "ok": false, "error": error});
    if let Some(rule) = rule {
        reply["rule"] = json!(rule);
    }
    reply
}

fn default_nan(width: usize) -> u64 {
    if width == 4 { 0x7fc0_0000 } else { 0x7ff8_0000_0000_0000 }
}

/// The decoded form of the float of `width` bytes with these IEEE bits: a number (-0.0 keeps its sign; an fp32 written
/// with its own shortest digits, never widened first), "inf", "-inf", "nan" (the default quiet NaN) or "nan:<hex>".
/// serde_json writes a NaN as null: the strings are made here.
fn float_json(bits: u64, width: usize) -> Value {
    let (nan, inf, text) = if width == 4 {
        let f = f32::from_bits(bits as u32);
        (f.is_nan(), f.is_infinite().then_some(f > 0.0), format!("{f:?}"))
    } else {
        let d = f64::from_bits(bits);
        (d.is_nan(), d.is_infinite().then_some(d > 0.0), format!("{d:?}"))
    };
    if nan {
        return if bits == default_nan(width) { json!("nan") } else { json!(format!("nan:{bits:0w$x}", w = width * 2)) };
    }
    if let Some(positive) = inf {
        return json!(if positive { "inf" } else { "-inf" });
    }
    // {:?} is the shortest decimal that reads back at this width ("-0.0", "0.1", "1e-45"): kept as written
    serde_json::from_str(&text).expect("a finite float's digits are JSON")
}

/// The bits at `width` bytes of a decoded form's float: a number, "inf", "-inf", "nan" or "nan:<hex>".
fn float_bits(value: &Value, width: usize) -> Result<u64, String> {
    match value {
        Value::Number(n) => {
            // the number's text parsed at the field's width (serde_json keeps -0.0 as a float)
            let text = n.to_string();
            if width == 4 {
                text.parse::<f32>().map(|f| f.to_bits() as u64).map_err(|e| e.to_string())
            } else {
                text.parse::<f64>().map(f64::to_bits).map_err(|e| e.to_string())
            }
        }
        Value::String(s) if s == "nan" => Ok(default_nan(width)),
        Value::String(s) if s.starts_with("nan:") => u64::from_str_radix(&s[4..], 16).map_err(|e| e.to_string()),
        Value::String(s) if s == "inf" || s == "-inf" => {
            let sign = if s == "inf" { 1.0 } else { -1.0 };
            Ok(if width == 4 { (f32::INFINITY * sign as f32).to_bits() as u64 } else { (f64::INFINITY * sign).to_bits() })
        }
        other => Err(format!("not a float: {other}")),
    }
}

fn to_hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn from_hex(text: &str) -> Result<Vec<u8>, String> {
    if text.len() % 2 != 0 {
        return Err("odd number of hex digits".into());
    }
    let digit = |c: u8| (c as char).to_digit(16).ok_or_else(|| format!("not a hex digit: {:?}", c as char));
    text.as_bytes().chunks(2).map(|pair| Ok((digit(pair[0])? * 16 + digit(pair[1])?) as u8)).collect()
}

/// {"width": 4|8, "bits": hex} -> the value written and the bits read back; {"hex": ...} -> it, read and written again.
fn value_probe(probe: &Value) -> Value {
    if let Some(text) = probe.get("hex").and_then(Value::as_str) {
        return match from_hex(text) {
            Ok(raw) => json!({"hex": to_hex(&raw)}),
            Err(e) => json!({"error": e}),
        };
    }
    let width = probe["width"].as_u64().unwrap_or(8) as usize;
    let bits = u64::from_str_radix(probe["bits"].as_str().unwrap_or(""), 16).unwrap_or(0);
    let value = float_json(bits, width);
    let reread: Value = serde_json::from_str(&value.to_string()).unwrap_or(Value::Null);
    let mut reply = Map::new();
    match float_bits(&reread, width) {
        Ok(back) => reply.insert("bits".into(), json!(format!("{back:0w$x}", w = width * 2))),
        Err(e) => reply.insert("error".into(), json!(e)),
    };
    reply.insert("value".into(), value);
    Value::Object(reply)
}
