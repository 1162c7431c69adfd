#pragma once
// An option whose value is one name of an enum's table (tomodem/core/names.hpp): the tool parses
// the name at the edge, the library gets the enum. An unknown name is an InputError naming the
// option, the value and the accepted names (exit 2), as from the library before.
#include <CLI/CLI.hpp>

#include <string>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/names.hpp"

namespace tomodem::cli {

/// "auto|tiff|mha": the value words --help shows and the completion offers (cli_docs.hpp).
template <class E, std::size_t N>
std::string choice_words(const NameTable<E, N>& table) {
  std::string out;
  for (std::size_t k = 0; k < N; ++k) out += (k ? "|" : "") + std::string(table[k].second);
  return out;
}

template <class E, std::size_t N>
CLI::Option* add_choice(CLI::App& app, const std::string& names, E& value, const NameTable<E, N>& table,
                        const std::string& help) {
  const std::string option = long_name(names);
  return app
      .add_option_function<std::string>(
          names, [&value, &table, option](const std::string& text) { value = parse_name(table, "", option, text); },
          help)
      ->default_str(name_of(table, value))
      ->type_name(choice_words(table));
}

}  // namespace tomodem::cli
