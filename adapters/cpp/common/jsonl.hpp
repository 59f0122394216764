// The adapter contract of adapters/README.md for C++ programs: JSON lines on stdin/stdout, or the same lines over
// a TCP or Unix socket (--listen), batches included. A program gives serve() its hello answer and a handler; this
// file does the rest: framing, ids, refusals, batches, sockets. JSON by nlohmann/json (Debian's
// nlohmann-json3-dev, header-only).
//
// What a C++ adapter must get right, all of it here:
//  * one answer per request, with the request's "id"; answers may come in any order;
//  * a request line may be a JSON array of requests (a batch) when hello said "batch": true: answer with an array;
//  * lines can be long (a 65,535-byte frame is 131,070 hex digits, and a batch holds up to 64 requests): read
//    whole lines, whatever their length, and never assume a line fits a fixed buffer;
//  * NaN and the infinities are not JSON numbers: they travel as strings ("nan", "nan:<hex bits>", "inf", "-inf");
//  * text that is not UTF-8 cannot be a JSON string: send {"hex": "..."} instead;
//  * a refusal of the implementation ("ok": false, with "rule" when known) is not a failure of the adapter
//    ("internal": true); never let an exception of the adapter itself look like a refusal.
#pragma once

#include <nlohmann/json.hpp>

#include <arpa/inet.h>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <netdb.h>
#include <new>
#include <stdexcept>
#include <string>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

namespace jsonl
{
  using json = nlohmann::json;

  //! The implementation refused the input (an invalid frame, a value it cannot hold); rule: a corpus rule or "".
  struct Refused : std::runtime_error
  {
    std::string rule;
    Refused(const std::string& what, std::string rule_ = "") : std::runtime_error(what), rule(std::move(rule_)) {}
  };

  //! The capability is absent (another suite, a byte order the implementation does not emit, an unknown op).
  struct Unsupported : std::runtime_error
  {
    using std::runtime_error::runtime_error;
  };

  // ------------------------------------------------------------------ values of the decoded form

  inline std::string
  to_hex(const uint8_t* data, size_t size)
  {
    static const char digits[] = "0123456789abcdef";
    std::string out(size * 2, '0');
    for (size_t i = 0; i < size; ++i)
    {
      out[2 * i] = digits[data[i] >> 4];
      out[2 * i + 1] = digits[data[i] & 15];
    }
    return out;
  }

  //! Bytes of a hex string (either case); throws Refused(rule "value-type") for anything else.
  inline std::string
  from_hex(const json& value, const std::string& where)
  {
    if (!value.is_string())
      throw Refused(where + ": expected a hex string", "value-type");
    const std::string& text = value.get_ref<const std::string&>();
    if (text.size() % 2)
      throw Refused(where + ": odd number of hex digits", "value-type");
    std::string out(text.size() / 2, '\0');
    for (size_t i = 0; i < text.size(); ++i)
    {
      int c = text[i], d = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10
                                               : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
      if (d < 0)
        throw Refused(where + ": not a hex digit in " + text.substr(0, 40), "value-type");
      out[i / 2] = char(out[i / 2] << 4 | d);
    }
    return out;
  }

  //! Whether bytes are UTF-8 as JSON strings need it (shortest forms, no surrogates, at most U+10FFFF).
  inline bool
  is_utf8(const std::string& s)
  {
    size_t i = 0, n = s.size();
    while (i < n)
    {
      unsigned c = uint8_t(s[i]), len = c < 0x80 ? 1 : (c >> 5) == 6 ? 2 : (c >> 4) == 14 ? 3 : (c >> 3) == 30 ? 4 : 0;
      if (len == 0 || i + len > n)
        return false;
      uint32_t cp = len == 1 ? c : c & (0x7F >> len);
      for (unsigned k = 1; k < len; ++k)
      {
        unsigned cc = uint8_t(s[i + k]);
        if ((cc >> 6) != 2)
          return false;
        cp = cp << 6 | (cc & 0x3F);
      }
      static const uint32_t smallest[] = {0, 0, 0x80, 0x800, 0x10000};
      if (cp < smallest[len] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF))
        return false;
      i += len;
    }
    return true;
  }

  //! Text as the decoded form writes it: a JSON string when it is UTF-8, else {"hex": ...}.
  inline json
  text_value(const std::string& bytes)
  {
    if (is_utf8(bytes))
      return bytes;
    return json{{"hex", to_hex(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size())}};
  }

  //! Bytes of a text value (a string, or {"hex": ...}); throws Refused(rule "value-type").
  inline std::string
  text_bytes(const json& value, const std::string& where)
  {
    if (value.is_string())
      return value.get<std::string>();
    if (value.is_object() && value.size() == 1 && value.contains("hex"))
      return from_hex(value["hex"], where);
    throw Refused(where + ": expected a string or {\"hex\": ...}", "value-type");
  }

  //! A float of the decoded form: a number, "inf", "-inf", "nan" (the default quiet NaN) or "nan:<hex bits>".
  template <typename Float, typename Bits>
  Float
  float_in(const json& value, const std::string& where)
  {
    static_assert(sizeof(Float) == sizeof(Bits), "same width");
    if (value.is_number())
      return static_cast<Float>(value.get<double>());
    if (!value.is_string())
      throw Refused(where + ": expected a number", "value-type");
    const std::string& text = value.get_ref<const std::string&>();
    if (text == "inf" || text == "-inf")
      return text[0] == '-' ? -std::numeric_limits<Float>::infinity() : std::numeric_limits<Float>::infinity();
    Bits bits = sizeof(Bits) == 4 ? Bits(0x7FC00000u) : Bits(0x7FF8000000000000ull);
    if (text.rfind("nan:", 0) == 0)
    {
      std::string raw = from_hex(json(text.substr(4)), where);
      if (raw.size() != sizeof(Bits))
        throw Refused(where + ": " + text + " is not a NaN of this width", "value-type");
      bits = 0;
      for (unsigned char c : raw)
        bits = Bits(bits << 8 | c);
    }
    else if (text != "nan")
      throw Refused(where + ": " + text.substr(0, 40) + " is not a float", "value-type");
    Float out;
    std::memcpy(&out, &bits, sizeof out);
    if (out == out)
      throw Refused(where + ": " + text + " is not a NaN", "value-type");
    return out;
  }

  //! A float as the decoded form writes it (the NaN's exact bits kept, the sign of zero kept).
  template <typename Float, typename Bits>
  json
  float_out(Float value)
  {
    if (value == value)
    {
      if (value == std::numeric_limits<Float>::infinity())
        return "inf";
      if (value == -std::numeric_limits<Float>::infinity())
        return "-inf";
      return static_cast<double>(value);
    }
    Bits bits;
    std::memcpy(&bits, &value, sizeof bits);
    if (bits == (sizeof(Bits) == 4 ? Bits(0x7FC00000u) : Bits(0x7FF8000000000000ull)))
      return "nan";
    uint8_t raw[sizeof(Bits)];
    for (size_t i = 0; i < sizeof(Bits); ++i)
      raw[i] = uint8_t(bits >> (8 * (sizeof(Bits) - 1 - i)));
    return "nan:" + to_hex(raw, sizeof raw);
  }

  //! An integer of the decoded form that fits Int; Refused "value-type" (not an integer) or "value-out-of-type".
  template <typename Int>
  Int
  int_in(const json& value, const std::string& where)
  {
    json number = value;
    if (value.is_string())  // 64-bit values may come as decimal strings
    {
      try
      {
        number = json::parse(value.get<std::string>());
      }
      catch (const json::exception&)
      {
        throw Refused(where + ": expected an integer", "value-type");
      }
    }
    if (number.is_number_unsigned())
    {
      uint64_t v = number.get<uint64_t>();
      if (v > uint64_t(std::numeric_limits<Int>::max()))
        throw Refused(where + ": " + number.dump() + " does not fit the field", "value-out-of-type");
      return Int(v);
    }
    if (number.is_number_integer())
    {
      int64_t v = number.get<int64_t>();
      if (v < int64_t(std::numeric_limits<Int>::min()) || (v > 0 && uint64_t(v) > uint64_t(std::numeric_limits<Int>::max())))
        throw Refused(where + ": " + number.dump() + " does not fit the field", "value-out-of-type");
      return Int(v);
    }
    if (number.is_number_float())  // an integer too large for 64 bits parses as a double
    {
      double v = number.get<double>();
      if (v == std::floor(v) && (v < double(std::numeric_limits<Int>::min()) ||
                                 v >= std::ldexp(1.0, std::numeric_limits<Int>::digits)))
        throw Refused(where + ": " + number.dump() + " does not fit the field", "value-out-of-type");
    }
    throw Refused(where + ": expected an integer", "value-type");
  }

  //! The string member `key` of a request, or "" when absent or not a string.
  inline std::string
  text_of(const json& request, const char* key)
  {
    auto it = request.find(key);
    return it != request.end() && it->is_string() ? it->get<std::string>() : std::string();
  }

  // ------------------------------------------------------------------ the protocol loop

  //! The answer to one request: the handler's object with "ok": true, or a refusal, or an absent capability.
  inline json
  answer(const json& request, const std::function<json(const json&)>& handle)
  {
    json out;
    try
    {
      out = handle(request);
      out["ok"] = true;
    }
    catch (const Refused& e)
    {
      out = {{"ok", false}, {"error", e.what()}};
      if (!e.rule.empty())
        out["rule"] = e.rule;
    }
    catch (const Unsupported& e)
    {
      out = {{"ok", false}, {"unsupported", true}, {"error", e.what()}};
    }
    catch (const std::bad_alloc&)
    {
      throw;  // out of memory is the implementation's failure, not the adapter's: let the program die (CRASH)
    }
    catch (const std::exception& e)
    {
      out = {{"ok", false}, {"internal", true}, {"error", std::string("adapter failed: ") + e.what()}};
    }
    auto id = request.is_object() ? request.find("id") : request.end();
    out["id"] = id != request.end() ? *id : json();
    return out;
  }

  //! Write all of `text` to `fd`; false when the reader is gone.
  inline bool
  write_all(int fd, const std::string& text)
  {
    size_t done = 0;
    while (done < text.size())
    {
      ssize_t n = ::write(fd, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR)
        continue;
      if (n <= 0)
        return false;
      done += size_t(n);
    }
    return true;
  }

  //! The longest line the suite reads (adapters/README.md); a batch's answers longer than that go one a line.
  constexpr size_t MAX_LINE = 1000000;

  //! Serve one stream (stdin/stdout or a connection) until its end: one answer line per request line.
  inline void
  serve_stream(int in, int out, const json& hello, const std::function<json(const json&)>& handle)
  {
    auto dispatch = [&](const json& request) {
      if (request.is_object() && request.value("op", "") == "hello")
        return answer(request, [&](const json&) { return hello; });
      return answer(request, handle);
    };
    std::string buffer, chunk(1 << 16, '\0');
    size_t scanned = 0;
    for (;;)
    {
      size_t end = buffer.find('\n', scanned);
      if (end == std::string::npos)
      {
        scanned = buffer.size();
        ssize_t n = ::read(in, &chunk[0], chunk.size());
        if (n < 0 && errno == EINTR)
          continue;
        if (n <= 0)
          return;  // end of input: the end of the run
        buffer.append(chunk, 0, size_t(n));
        continue;
      }
      std::string line = buffer.substr(0, end);
      buffer.erase(0, end + 1);
      scanned = 0;
      std::string reply;
      try
      {
        json request = json::parse(line);
        if (request.is_array())
        {
          json answers = json::array();
          for (const json& one : request)
            answers.push_back(dispatch(one));
          reply = answers.dump() + "\n";
          if (reply.size() > MAX_LINE)  // the suite reads lines of up to 1 MB: then one answer a line
          {
            reply.clear();
            for (const json& one : answers)
              reply += one.dump() + "\n";
          }
        }
        else
          reply = dispatch(request).dump() + "\n";
      }
      catch (const json::parse_error& e)
      {
        reply = json{{"id", nullptr}, {"ok", false}, {"internal", true},
                     {"error", std::string("bad request: ") + e.what()}}.dump() + "\n";
      }
      if (!write_all(out, reply))
        return;
    }
  }

  //! A listening socket for tcp://IP:PORT, tcp://[IPv6]:PORT or unix:PATH (numeric addresses only: no lookups).
  inline int
  listen_on(const std::string& where, std::string& bound)
  {
    int fd = -1;
    if (where.rfind("unix:", 0) == 0)
    {
      sockaddr_un addr{};
      std::string path = where.substr(5);
      if (path.empty() || path.size() >= sizeof addr.sun_path)
        throw std::runtime_error("unix socket path empty or too long: " + path);
      addr.sun_family = AF_UNIX;
      std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
      fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
      if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0)
        throw std::runtime_error("cannot bind " + where + ": " + std::strerror(errno));
      bound = where;
    }
    else if (where.rfind("tcp://", 0) == 0)
    {
      std::string rest = where.substr(6), host, port;
      size_t colon = rest.rfind(':');
      if (colon == std::string::npos)
        throw std::runtime_error("expected tcp://HOST:PORT, got " + where);
      host = rest.substr(0, colon);
      port = rest.substr(colon + 1);
      if (host.size() > 1 && host.front() == '[' && host.back() == ']')
        host = host.substr(1, host.size() - 2);
      addrinfo hints{}, *found = nullptr;
      hints.ai_flags = AI_NUMERICHOST | AI_NUMERICSERV | AI_PASSIVE;
      hints.ai_socktype = SOCK_STREAM;
      if (::getaddrinfo(host.c_str(), port.c_str(), &hints, &found) != 0)
        throw std::runtime_error("not a numeric address and port: " + where);
      fd = ::socket(found->ai_family, SOCK_STREAM, 0);
      int yes = 1;
      ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
      bool ok = fd >= 0 && ::bind(fd, found->ai_addr, found->ai_addrlen) == 0;
      ::freeaddrinfo(found);
      if (!ok)
        throw std::runtime_error("cannot bind " + where + ": " + std::strerror(errno));
      sockaddr_storage addr{};
      socklen_t len = sizeof addr;
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
      char text[INET6_ADDRSTRLEN] = "";
      bool v6 = addr.ss_family == AF_INET6;
      const void* ip = v6 ? static_cast<const void*>(&reinterpret_cast<sockaddr_in6*>(&addr)->sin6_addr)
                          : static_cast<const void*>(&reinterpret_cast<sockaddr_in*>(&addr)->sin_addr);
      ::inet_ntop(addr.ss_family, ip, text, sizeof text);
      unsigned p = ntohs(v6 ? reinterpret_cast<sockaddr_in6*>(&addr)->sin6_port : reinterpret_cast<sockaddr_in*>(&addr)->sin_port);
      bound = std::string("tcp://") + (v6 ? "[" : "") + text + (v6 ? "]" : "") + ":" + std::to_string(p);
    }
    else
      throw std::runtime_error("--listen takes tcp://IP:PORT or unix:PATH, not " + where);
    if (::listen(fd, 16) != 0)
      throw std::runtime_error("cannot listen on " + where + ": " + std::strerror(errno));
    return fd;
  }

  //! Serve each connection in a child process of its own, so that a crash of the implementation drops only that
  //! connection (the suite sees a dropped connection, reconnects and blames the case) and the server lives on.
  inline int
  serve_socket(const std::string& where, const json& hello, const std::function<json(const json&)>& handle)
  {
    std::string bound;
    int fd = listen_on(where, bound);
    std::signal(SIGCHLD, SIG_IGN);  // children are reaped by the kernel
    std::signal(SIGPIPE, SIG_IGN);
    std::printf("listening %s\n", bound.c_str());  // the first line on stdout: where to connect (port 0 chosen)
    std::fflush(stdout);
    for (;;)
    {
      int conn = ::accept(fd, nullptr, nullptr);
      if (conn < 0)
      {
        if (errno == EINTR || errno == ECONNABORTED)
          continue;
        std::perror("accept");
        return 1;
      }
      pid_t child = ::fork();
      if (child == 0)
      {
        ::close(fd);
        serve_stream(conn, conn, hello, handle);
        ::_exit(0);
      }
      ::close(conn);
    }
  }

  //! main() of an adapter: stdin/stdout, or --listen ADDRESS.
  inline int
  run(int argc, char** argv, const json& hello, const std::function<json(const json&)>& handle)
  {
    std::signal(SIGPIPE, SIG_IGN);
    for (int i = 1; i < argc; ++i)
    {
      if (std::strcmp(argv[i], "--listen") == 0 && i + 1 < argc)
      {
        try
        {
          return serve_socket(argv[i + 1], hello, handle);
        }
        catch (const std::exception& e)
        {
          std::fprintf(stderr, "%s: %s\n", argv[0], e.what());
          return 2;
        }
      }
    }
    serve_stream(0, 1, hello, handle);
    return 0;
  }
}
