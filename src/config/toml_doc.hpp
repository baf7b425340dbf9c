// TOML files of the formats beside the run config (a study file, a study folder's manifest) as plain values,
// read and written by the TOML library the config is read with: a format's reader walks the tree with its own
// keys and messages, and only src/config includes the library.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "common/check.hpp"

namespace divcoll::config {

// a TOML text that does not parse: what() is "<origin>: <the library's reason> at line <line>"
struct TomlSyntaxError : InputError {
  TomlSyntaxError(const std::string& origin, const std::string& reason, int line);
  std::string reason;  // the library's description alone
  int line = 0;
};

// one TOML value; a table keeps its keys in the library's order (by key), as it reads and writes them
struct TomlValue {
  enum class Kind { table, array, string, integer, floating, boolean, other };  // other: dates and times
  Kind kind = Kind::table;
  std::string string;
  std::int64_t integer = 0;
  double floating = 0;
  bool boolean = false;
  std::vector<TomlValue> items;                         // array
  std::vector<std::pair<std::string, TomlValue>> keys;  // table
  int line = 0;                                         // where a value read from a text starts

  static TomlValue of(const std::string& s);
  static TomlValue of(std::int64_t i);
  static TomlValue of(double d);
  static TomlValue list(std::vector<TomlValue> items);
  static TomlValue list(const std::vector<std::string>& strings);
  // table: sets `key` (replacing its value)
  TomlValue& set(const std::string& key, TomlValue value);

  bool is(Kind k) const { return kind == k; }
  // table: the value of `key`, nullptr if there is none (or this is no table)
  const TomlValue* find(const std::string& key) const;
  // table: the value of `key` if it is of that kind, else `otherwise` (a number: integer or floating)
  std::string string_or(const std::string& key, const std::string& otherwise) const;
  std::int64_t integer_or(const std::string& key, std::int64_t otherwise) const;
  double number_or(const std::string& key, double otherwise) const;
};

// a TOML text as a table; TomlSyntaxError naming `origin` if it does not parse
TomlValue parse_toml(const std::string& text, const std::string& origin);
// a table as the library writes it
std::string toml_text(const TomlValue& table);

}  // namespace divcoll::config
