#include "config/toml_doc.hpp"

#include <sstream>

#include "config/toml_parse.hpp"

namespace divcoll::config {

TomlSyntaxError::TomlSyntaxError(const std::string& origin, const std::string& reason_, int line_)
    : InputError(origin + ": " + reason_ + " at line " + std::to_string(line_)), reason(reason_), line(line_) {}

toml::table parse_toml_table(const std::string& text, const std::string& origin) {
  try {
    return toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    throw TomlSyntaxError(origin, std::string(e.description()), static_cast<int>(e.source().begin.line));
  }
}

namespace {

TomlValue from_node(const toml::node& n) {
  TomlValue v;
  v.line = static_cast<int>(n.source().begin.line);
  if (const toml::table* t = n.as_table()) {
    v.kind = TomlValue::Kind::table;
    for (auto&& [k, e] : *t) v.keys.emplace_back(std::string(k.str()), from_node(e));
  } else if (const toml::array* a = n.as_array()) {
    v.kind = TomlValue::Kind::array;
    for (const toml::node& e : *a) v.items.push_back(from_node(e));
  } else if (n.is_string()) {
    v.kind = TomlValue::Kind::string, v.string = n.as_string()->get();
  } else if (n.is_integer()) {
    v.kind = TomlValue::Kind::integer, v.integer = n.as_integer()->get();
  } else if (n.is_floating_point()) {
    v.kind = TomlValue::Kind::floating, v.floating = n.as_floating_point()->get();
  } else if (n.is_boolean()) {
    v.kind = TomlValue::Kind::boolean, v.boolean = n.as_boolean()->get();
  } else {
    v.kind = TomlValue::Kind::other;
  }
  return v;
}

toml::table to_table(const TomlValue& v);

toml::array to_array(const TomlValue& v) {
  toml::array a;
  for (const TomlValue& e : v.items) {
    switch (e.kind) {
      case TomlValue::Kind::table: a.push_back(to_table(e)); break;
      case TomlValue::Kind::array: a.push_back(to_array(e)); break;
      case TomlValue::Kind::string: a.push_back(e.string); break;
      case TomlValue::Kind::integer: a.push_back(e.integer); break;
      case TomlValue::Kind::floating: a.push_back(e.floating); break;
      case TomlValue::Kind::boolean: a.push_back(e.boolean); break;
      case TomlValue::Kind::other: break;
    }
  }
  return a;
}

toml::table to_table(const TomlValue& v) {
  toml::table t;
  for (const auto& [k, e] : v.keys) {
    switch (e.kind) {
      case TomlValue::Kind::table: t.insert(k, to_table(e)); break;
      case TomlValue::Kind::array: t.insert(k, to_array(e)); break;
      case TomlValue::Kind::string: t.insert(k, e.string); break;
      case TomlValue::Kind::integer: t.insert(k, e.integer); break;
      case TomlValue::Kind::floating: t.insert(k, e.floating); break;
      case TomlValue::Kind::boolean: t.insert(k, e.boolean); break;
      case TomlValue::Kind::other: break;
    }
  }
  return t;
}

}  // namespace

TomlValue TomlValue::of(const std::string& s) {
  TomlValue v;
  v.kind = Kind::string, v.string = s;
  return v;
}
TomlValue TomlValue::of(std::int64_t i) {
  TomlValue v;
  v.kind = Kind::integer, v.integer = i;
  return v;
}
TomlValue TomlValue::of(double d) {
  TomlValue v;
  v.kind = Kind::floating, v.floating = d;
  return v;
}
TomlValue TomlValue::list(std::vector<TomlValue> items) {
  TomlValue v;
  v.kind = Kind::array, v.items = std::move(items);
  return v;
}
TomlValue TomlValue::list(const std::vector<std::string>& strings) {
  std::vector<TomlValue> items;
  for (const std::string& s : strings) items.push_back(of(s));
  return list(std::move(items));
}

TomlValue& TomlValue::set(const std::string& key, TomlValue value) {
  for (auto& [k, e] : keys)
    if (k == key) return e = std::move(value);
  keys.emplace_back(key, std::move(value));
  return keys.back().second;
}

const TomlValue* TomlValue::find(const std::string& key) const {
  if (kind != Kind::table) return nullptr;
  for (const auto& [k, e] : keys)
    if (k == key) return &e;
  return nullptr;
}

std::string TomlValue::string_or(const std::string& key, const std::string& otherwise) const {
  const TomlValue* v = find(key);
  return v && v->is(Kind::string) ? v->string : otherwise;
}

std::int64_t TomlValue::integer_or(const std::string& key, std::int64_t otherwise) const {
  const TomlValue* v = find(key);
  return v && v->is(Kind::integer) ? v->integer : otherwise;
}

double TomlValue::number_or(const std::string& key, double otherwise) const {
  const TomlValue* v = find(key);
  if (v && v->is(Kind::floating)) return v->floating;
  return v && v->is(Kind::integer) ? static_cast<double>(v->integer) : otherwise;
}

TomlValue parse_toml(const std::string& text, const std::string& origin) { return from_node(parse_toml_table(text, origin)); }

std::string toml_text(const TomlValue& table) {
  std::ostringstream out;
  out << to_table(table);
  return out.str();
}

}  // namespace divcoll::config
