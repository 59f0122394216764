/* A starter adapter for imc-conformance (ADAPTER-CONTRACT.md): the protocol loop, answering every request "unsupported"
 * until the TODOs call your implementation, and the decoded form's values done right (floats by their bits at the
 * field's width: -0.0, NaN payloads, fp32 kept 32-bit; hex). With --values it reads value probes instead (what the
 * suite's tests check the helpers with). JSON: cJSON (Debian's libcjson-dev); numbers it cannot write right (-0.0,
 * an fp32's own digits) go in as raw text. Build: cc -O2 adapter.c -lcjson -o starter
 */
#define _GNU_SOURCE
#include <cjson/cJSON.h>
#include <ctype.h>
#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const uint64_t DEFAULT_NAN32 = 0x7fc00000u, DEFAULT_NAN64 = 0x7ff8000000000000u;

/* The decoded form of the float of `width` bytes (4 or 8) with these IEEE bits: a number (-0.0 keeps its sign; an fp32
 * written from a float, never widened first), "inf", "-inf", "nan" (the default quiet NaN) or "nan:<hex bits>". */
static cJSON *float_json(uint64_t bits, int width) {
    char text[40];
    double x;
    if (width == 4) {
        uint32_t b = (uint32_t)bits;
        float f;
        memcpy(&f, &b, 4);
        if (isnan(f)) {
            if (bits == DEFAULT_NAN32) return cJSON_CreateString("nan");
            snprintf(text, sizeof text, "nan:%08" PRIx32, b);  /* the bit pattern, most significant digit first */
            return cJSON_CreateString(text);
        }
        x = f;
        if (!isinf(f)) snprintf(text, sizeof text, "%.9g", f);  /* 9 digits always read back to the same float */
    } else {
        memcpy(&x, &bits, 8);
        if (isnan(x)) {
            if (bits == DEFAULT_NAN64) return cJSON_CreateString("nan");
            snprintf(text, sizeof text, "nan:%016" PRIx64, bits);
            return cJSON_CreateString(text);
        }
        if (!isinf(x)) snprintf(text, sizeof text, "%.17g", x);  /* 17 digits for a double */
    }
    if (isinf(x)) return cJSON_CreateString(x > 0 ? "inf" : "-inf");
    if (!strpbrk(text, ".eEn")) strcat(text, ".0");  /* a float, never an integer: -0 would read back as 0 */
    return cJSON_CreateRaw(text);
}

/* The bits at `width` bytes of a decoded form's float (a number, "inf", "-inf", "nan", "nan:<hex>"); 0 on success. */
static int float_bits(const cJSON *value, int width, uint64_t *bits) {
    if (cJSON_IsNumber(value)) {
        /* cJSON keeps a double (-0.0 keeps its sign): an fp32 field's shortest decimal, as the suite writes it,
         * rounds to the same float through the double */
        double d = value->valuedouble;
        if (width == 4) {
            float f = (float)d;
            uint32_t b;
            memcpy(&b, &f, 4);
            *bits = b;
        } else {
            memcpy(bits, &d, 8);
        }
        return 0;
    }
    if (!cJSON_IsString(value)) return -1;
    const char *s = value->valuestring;
    if (strcmp(s, "nan") == 0) {
        *bits = width == 4 ? DEFAULT_NAN32 : DEFAULT_NAN64;
        return 0;
    }
    if (strncmp(s, "nan:", 4) == 0) {
        char *end;
        *bits = strtoull(s + 4, &end, 16);
        return *end == '\0' && end != s + 4 ? 0 : -1;
    }
    if (strcmp(s, "inf") == 0 || strcmp(s, "-inf") == 0) {
        if (width == 4) {
            float f = s[0] == '-' ? -INFINITY : INFINITY;
            uint32_t b;
            memcpy(&b, &f, 4);
            *bits = b;
        } else {
            double d = s[0] == '-' ? -INFINITY : INFINITY;
            memcpy(bits, &d, 8);
        }
        return 0;
    }
    return -1;
}

/* Hex of `n` bytes, lowercase, two digits a byte (free() it). */
static char *to_hex(const unsigned char *data, size_t n) {
    char *out = malloc(2 * n + 1);
    if (!out) return NULL;
    for (size_t i = 0; i < n; i++) snprintf(out + 2 * i, 3, "%02x", data[i]);
    out[2 * n] = '\0';
    return out;
}

/* The bytes of hex text (either case) into a new buffer (free() it) of *n bytes; NULL if it is not hex. */
static unsigned char *from_hex(const char *text, size_t *n) {
    size_t len = strlen(text);
    if (len % 2) return NULL;
    unsigned char *out = malloc(len / 2 + 1);
    if (!out) return NULL;
    for (size_t i = 0; i < len / 2; i++) {
        unsigned int byte;
        if (!isxdigit((unsigned char)text[2 * i]) || !isxdigit((unsigned char)text[2 * i + 1]) ||
            sscanf(text + 2 * i, "%2x", &byte) != 1) {
            free(out);
            return NULL;
        }
        out[i] = (unsigned char)byte;
    }
    *n = len / 2;
    return out;
}

static cJSON *unsupported(cJSON *reply, const char *why) {
    cJSON_AddFalseToObject(reply, "ok");
    cJSON_AddTrueToObject(reply, "unsupported");
    cJSON_AddStringToObject(reply, "error", why);
    return reply;
}

static cJSON *answer(const cJSON *request) {
    cJSON *reply = cJSON_CreateObject();
    cJSON_AddItemToObject(reply, "id", cJSON_Duplicate(cJSON_GetObjectItemCaseSensitive(request, "id"), 1));
    const cJSON *op = cJSON_GetObjectItemCaseSensitive(request, "op");
    const char *name = cJSON_IsString(op) ? op->valuestring : "";
    if (strcmp(name, "hello") == 0) {
        cJSON_AddTrueToObject(reply, "ok");
        cJSON_AddStringToObject(reply, "implementation", "my-imc 0.0.0 (starter: nothing implemented yet)"); /* TODO */
        const char *suites[] = {"imc"}, *orders[] = {"le", "be"};  /* TODO: the byte orders your implementation emits */
        cJSON_AddItemToObject(reply, "suites", cJSON_CreateStringArray(suites, 1));
        cJSON_AddItemToObject(reply, "byte_orders", cJSON_CreateStringArray(orders, 2));
        return reply;
    }
    if (strcmp(name, "encode") == 0) {
        /* TODO: build your message from the "message" object (read floats with float_bits(value, 4 or 8, &bits)),
         * serialize it in "byte_order", and answer "ok": true, "frame": to_hex(frame, size). The implementation's own
         * error return is its answer, not the adapter's bug:
         *   if (imc_serialize(&msg, buf, &size) != 0) { cJSON_AddFalseToObject(reply, "ok");
         *       cJSON_AddStringToObject(reply, "error", imc_strerror()); return reply; }   (a refusal, no rule)
         * a crash inside it (SIGSEGV on a NULL list element) ends the program: the suite records a CRASH of that case. */
        return unsupported(reply, "encode is not implemented yet");
    }
    if (strcmp(name, "decode") == 0) {
        /* TODO: from_hex(frame); deserialize it; answer its abbrev, the five header fields and every field (floats
         * with float_json(bits, 4 or 8)). A refusal: "ok": false, "error": ..., and "rule" only when the check that
         * refused is that rule's check. */
        return unsupported(reply, "decode is not implemented yet");
    }
    return unsupported(reply, "unknown op");
}

/* {"width": 4|8, "bits": hex} -> the value written and the bits read back; {"hex": ...} -> it, read and written. */
static cJSON *value_probe(const cJSON *probe) {
    cJSON *reply = cJSON_CreateObject();
    const cJSON *hex = cJSON_GetObjectItemCaseSensitive(probe, "hex");
    if (cJSON_IsString(hex)) {
        size_t n = 0;
        unsigned char *raw = from_hex(hex->valuestring, &n);
        char *again = raw ? to_hex(raw, n) : NULL;
        cJSON_AddStringToObject(reply, again ? "hex" : "error", again ? again : "not hex");
        free(raw);
        free(again);
        return reply;
    }
    int width = cJSON_GetObjectItemCaseSensitive(probe, "width")->valueint;
    uint64_t bits = strtoull(cJSON_GetObjectItemCaseSensitive(probe, "bits")->valuestring, NULL, 16), back = 0;
    cJSON *value = float_json(bits, width);
    char *text = cJSON_PrintUnformatted(value);
    cJSON *reread = cJSON_Parse(text);
    char shown[20];
    if (float_bits(reread, width, &back) == 0) {
        snprintf(shown, sizeof shown, width == 4 ? "%08" PRIx64 : "%016" PRIx64, back);
        cJSON_AddStringToObject(reply, "bits", shown);
    }
    cJSON_AddItemToObject(reply, "value", value);
    cJSON_Delete(reread);
    free(text);
    return reply;
}

int main(int argc, char **argv) {
    int values = argc > 1 && strcmp(argv[1], "--values") == 0;
    char *line = NULL;
    size_t size = 0;
    while (getline(&line, &size, stdin) != -1) {  /* lines of any length; the end of input is the end of the run */
        if (strspn(line, " \t\r\n") == strlen(line)) continue;
        cJSON *request = cJSON_Parse(line), *reply;
        if (!cJSON_IsObject(request)) {
            reply = cJSON_CreateObject();
            cJSON_AddNullToObject(reply, "id");
            cJSON_AddFalseToObject(reply, "ok");
            cJSON_AddTrueToObject(reply, "internal");
            cJSON_AddStringToObject(reply, "error", "a request that is not a JSON object");
        } else {
            reply = values ? value_probe(request) : answer(request);
        }
        char *text = cJSON_PrintUnformatted(reply);
        fputs(text, stdout);
        fputc('\n', stdout);
        fflush(stdout);  /* every line, at once: a pipe's stdout is fully buffered otherwise */
        free(text);
        cJSON_Delete(reply);
        cJSON_Delete(request);
    }
    free(line);
    return 0;
}
