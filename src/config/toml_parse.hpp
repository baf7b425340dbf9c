// inside src/config: the one call that parses a TOML text (the run config, the environments, toml_doc.hpp's formats)
#pragma once

#include <toml++/toml.h>

#include <string>

namespace divcoll::config {

// `text` parsed; TomlSyntaxError (config/toml_doc.hpp) naming `origin`, the reason and the line if it does not parse
toml::table parse_toml_table(const std::string& text, const std::string& origin);

}  // namespace divcoll::config
