#pragma once
// An option whose value is one name of an enum's table (tomodem/core/names.hpp): the tool parses
// the name at the edge, the library gets the enum. An unknown name is an InputError naming the
// option, the value and the accepted names (exit 2), as from the library before.
#include <CLI/CLI.hpp>

#include <string>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/names.hpp"

namespace tomodem::cli {

template <class E, std::size_t N>
CLI::Option* add_choice(CLI::App& app, const std::string& names, E& value, const NameTable<E, N>& table,
                        const std::string& help) {
  const std::string option = long_name(names);
  return app
      .add_option_function<std::string>(
          names, [&value, &table, option](const std::string& text) { value = parse_name(table, "", option, text); },
          help)
      ->default_str(name_of(table, value));
}

}  // namespace tomodem::cli
