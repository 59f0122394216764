// DUNE's own IMC codec (C++, from the imcpy sdist's copy of DUNE) behind the adapter contract of adapters/README.md.
//
//   dune-imc-adapter                  JSON lines on stdin/stdout (imc-conformance run --adapter dune-cpp)
//   dune-imc-adapter --listen ADDR    the same over tcp://IP:PORT or unix:PATH (run --adapter-socket ADDR)
//
// decode: DUNE::IMC::Packet::deserialize on the frame; encode: a message from DUNE::IMC::Factory, its fields set,
// then Packet::serialize: exactly what a C++ program using DUNE does. The fields of each message are named in
// fields.inc, generated from the suite's definitions.json (generate_fields.py); the visitors below move each field
// between the decoded form and DUNE by its C++ type. DUNE emits little-endian only (the host's order).

#include <DUNE/IMC/Definitions.hpp>
#include <DUNE/IMC/Exceptions.hpp>
#include <DUNE/IMC/Factory.hpp>
#include <DUNE/IMC/Packet.hpp>

#include "jsonl.hpp"

#include <set>
#include <vector>

using jsonl::json;
using jsonl::Refused;
namespace IMC = DUNE::IMC;

#include "fields.inc"

namespace
{
  // DUNE's error texts that name a rule of vectors/imc/rules.json (the others say too little to name one).
  const std::pair<const char*, const char*> RULES[] = {
    {"invalid CRC", "crc"}, {"invalid synchronization number", "sync"}, {"invalid message size", "size-limit"}};

  std::string
  rule_of(const std::string& text)
  {
    for (const auto& r : RULES)
      if (text.rfind(r.first, 0) == 0)
        return r.second;
    return "";
  }

  json message_out(const IMC::Message* m);
  IMC::Message* message_in(const json& value, const std::string& where);

  // ---------------------------------------------------------------- DUNE -> decoded form

  //! Visits a DUNE message's fields, writing each into `fields` by its C++ type.
  struct Reader
  {
    json fields = json::object();

    template <typename Int>
    void operator()(const char* name, const Int& value) { fields[name] = value; }
    void operator()(const char* name, const uint8_t& value) { fields[name] = unsigned(value); }
    void operator()(const char* name, const int8_t& value) { fields[name] = int(value); }
    void operator()(const char* name, const float& value) { fields[name] = jsonl::float_out<float, uint32_t>(value); }
    void operator()(const char* name, const double& value) { fields[name] = jsonl::float_out<double, uint64_t>(value); }
    void operator()(const char* name, const std::string& value) { fields[name] = jsonl::text_value(value); }
    void operator()(const char* name, const std::vector<char>& value)
    {
      fields[name] = jsonl::to_hex(reinterpret_cast<const uint8_t*>(value.data()), value.size());
    }
    template <typename T>
    void operator()(const char* name, const IMC::InlineMessage<T>& value)
    {
      fields[name] = value.isNull() ? json() : message_out(value.get());
    }
    template <typename T>
    void operator()(const char* name, const IMC::MessageList<T>& value)
    {
      json items = json::array();
      for (const T* element : value)
        items.push_back(element ? message_out(element) : json());
      fields[name] = items;
    }
  };

  json
  message_out(const IMC::Message* m)
  {
    Reader reader;
    visit_message(reader, const_cast<IMC::Message&>(*m));  // a message the definitions lack: no fields
    return {{"abbrev", m->getName()}, {"fields", reader.fields}};
  }

  // ---------------------------------------------------------------- decoded form -> DUNE

  //! Visits a DUNE message's fields, setting each that `fields` gives (absent ones keep DUNE's defaults).
  struct Writer
  {
    const json& fields;
    std::string where;
    std::set<std::string> seen;

    const json*
    value(const char* name)
    {
      auto it = fields.find(name);
      if (it == fields.end())
        return nullptr;
      seen.insert(name);
      return &*it;
    }

    template <typename Int>
    void operator()(const char* name, Int& member)
    {
      if (const json* v = value(name))
        member = jsonl::int_in<Int>(*v, where + name);
    }
    void operator()(const char* name, float& member)
    {
      if (const json* v = value(name))
        member = jsonl::float_in<float, uint32_t>(*v, where + name);
    }
    void operator()(const char* name, double& member)
    {
      if (const json* v = value(name))
        member = jsonl::float_in<double, uint64_t>(*v, where + name);
    }
    void operator()(const char* name, std::string& member)
    {
      if (const json* v = value(name))
        member = jsonl::text_bytes(*v, where + name);
    }
    void operator()(const char* name, std::vector<char>& member)
    {
      if (const json* v = value(name))
      {
        std::string raw = jsonl::from_hex(*v, where + name);
        member.assign(raw.begin(), raw.end());
      }
    }
    template <typename T>
    void operator()(const char* name, IMC::InlineMessage<T>& member)
    {
      if (const json* v = value(name))
      {
        std::unique_ptr<IMC::Message> m(message_in(*v, where + name));
        if (!m)
          member.clear();
        else
          member.set(*typed<T>(m.get(), where + name));
      }
    }
    template <typename T>
    void operator()(const char* name, IMC::MessageList<T>& member)
    {
      const json* v = value(name);
      if (!v)
        return;
      if (!v->is_array())
        throw Refused(where + name + ": a message-list must be an array", "value-type");
      member.clear();
      for (const json& element : *v)
      {
        std::unique_ptr<IMC::Message> m(message_in(element, where + name));
        member.push_back(m ? typed<T>(m.get(), where + name) : static_cast<const T*>(nullptr));
      }
    }

    //! The message as the member's C++ type: a message of another type cannot be stored there.
    template <typename T>
    static const T*
    typed(const IMC::Message* m, const std::string& where)
    {
      const T* out = dynamic_cast<const T*>(m);
      if (!out)
        throw Refused(where + ": DUNE's member cannot hold a " + m->getName());
      return out;
    }
  };

  //! A DUNE message for a decoded message (null -> nullptr), owned by the caller.
  IMC::Message*
  message_in(const json& value, const std::string& where)
  {
    if (value.is_null())
      return nullptr;
    if (!value.is_object() || !value.contains("abbrev") || !value["abbrev"].is_string())
      throw Refused(where + ": a message must be an object with an abbrev", "value-type");
    std::string abbrev = value["abbrev"].get<std::string>();
    IMC::Message* m = nullptr;
    try
    {
      m = IMC::Factory::produce(abbrev);
    }
    catch (const std::exception&)
    {
    }
    if (!m)
      throw Refused("DUNE does not know message " + abbrev, "unknown-message");
    std::unique_ptr<IMC::Message> owned(m);
    json empty = json::object();
    const json& fields = value.contains("fields") ? value["fields"] : empty;
    if (!fields.is_object())
      throw Refused(abbrev + ": fields must be an object", "value-type");
    Writer writer{fields, abbrev + "."};
    if (!visit_message(writer, *m))
      throw jsonl::Unsupported("DUNE knows " + abbrev + " but the definitions do not");
    for (const auto& item : fields.items())
      if (!writer.seen.count(item.key()))
        throw Refused(abbrev + " has no field '" + item.key() + "'", "unknown-field");
    return owned.release();
  }

  // ---------------------------------------------------------------- the operations

  json
  decode(const json& request)
  {
    std::string frame = jsonl::from_hex(request.value("frame", json()), "frame");
    std::unique_ptr<IMC::Message> m;
    try
    {
      // DUNE takes the length as a uint16_t, as every C++ caller passes it.
      m.reset(IMC::Packet::deserialize(reinterpret_cast<const uint8_t*>(frame.data()), frame.size()));
    }
    catch (const std::runtime_error& e)  // DUNE's refusals: InvalidSync, InvalidCrc, BufferTooShort, ...
    {
      throw Refused(e.what(), rule_of(e.what()));
    }
    json out = message_out(m.get());
    out["header"] = {{"timestamp", jsonl::float_out<double, uint64_t>(m->getTimeStamp())},
                     {"src", m->getSource()}, {"src_ent", m->getSourceEntity()},
                     {"dst", m->getDestination()}, {"dst_ent", m->getDestinationEntity()}};
    return {{"message", out}};
  }

  json
  encode(const json& request)
  {
    if (jsonl::text_of(request, "byte_order") != "le")
      throw jsonl::Unsupported("DUNE emits little-endian frames only (its host's order)");
    const json& message = request.contains("message") ? request["message"] : json();
    std::unique_ptr<IMC::Message> m(message_in(message, ""));
    if (!m)
      throw Refused("the message is null", "value-type");
    json header = message.value("header", json::object());
    if (!header.is_object())
      throw Refused("header must be an object", "value-type");
    // The header as the definitions' defaults give it, then as the message gives it.
    m->setTimeStamp(jsonl::float_in<double, uint64_t>(header.value("timestamp", json(-1.0)), "header.timestamp"));
    m->setSource(jsonl::int_in<uint16_t>(header.value("src", json(0xFFFF)), "header.src"));
    m->setSourceEntity(jsonl::int_in<uint8_t>(header.value("src_ent", json(0xFF)), "header.src_ent"));
    m->setDestination(jsonl::int_in<uint16_t>(header.value("dst", json(0xFFFF)), "header.dst"));
    m->setDestinationEntity(jsonl::int_in<uint8_t>(header.value("dst_ent", json(0xFF)), "header.dst_ent"));
    std::vector<uint8_t> buffer(m->getSerializationSize());
    uint16_t written;
    try
    {
      written = IMC::Packet::serialize(m.get(), buffer.data(), buffer.size());
    }
    catch (const std::runtime_error& e)  // InvalidMessageSize
    {
      throw Refused(e.what(), rule_of(e.what()));
    }
    return {{"frame", jsonl::to_hex(buffer.data(), written)}};
  }

  json
  handle(const json& request)
  {
    if (jsonl::text_of(request, "suite") != "imc")
      throw jsonl::Unsupported("DUNE implements only the imc suite");
    std::string op = jsonl::text_of(request, "op");
    if (op == "decode")
      return decode(request);
    if (op == "encode")
      return encode(request);
    throw jsonl::Unsupported("unknown op");
  }
}

int
main(int argc, char** argv)
{
  json hello = {{"implementation", "DUNE IMC codec (C++, imcpy " IMCPY_VERSION " sdist, IMC " DUNE_IMC_CONST_VERSION ")"},
                {"suites", {"imc"}}, {"byte_orders", {"le"}}, {"batch", true}, {"errata", "dune"}};
  return jsonl::run(argc, argv, hello, handle);
}
