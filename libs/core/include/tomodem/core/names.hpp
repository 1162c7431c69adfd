#pragma once
// Names of the enums in the library APIs (issue 17): the libraries take enums and structs; the
// tool drivers and configuration readers turn the names a user typed into them at the edge, and
// summaries print the same names back. One table per enum, next to it, drives all three.
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tomodem/core/error.hpp"

namespace tomodem {

/// (value, name) rows, in the order messages list them.
template <class E, std::size_t N>
using NameTable = std::array<std::pair<E, const char*>, N>;

/// The name of `v` ("?" for a value the table lacks: a programming error, never user input).
template <class E, std::size_t N>
const char* name_of(const NameTable<E, N>& table, E v) {
  for (const auto& [e, s] : table)
    if (e == v) return s;
  return "?";
}

/// The value named `name`; nullopt for an unknown name, so the caller can say where it came from.
template <class E, std::size_t N>
std::optional<E> value_of(const NameTable<E, N>& table, std::string_view name) {
  for (const auto& [e, s] : table)
    if (name == s) return e;
  return std::nullopt;
}

/// The names in table order (for readers that take a list of choices).
template <class E, std::size_t N>
std::vector<std::string> name_list(const NameTable<E, N>& table) {
  std::vector<std::string> out;
  for (const auto& row : table) out.push_back(row.second);
  return out;
}

/// "a, b or c": the accepted names for messages.
template <class E, std::size_t N>
std::string names_of(const NameTable<E, N>& table) {
  std::string out;
  for (std::size_t k = 0; k < N; ++k) out += (k == 0 ? "" : (k + 1 == N ? " or " : ", ")) + std::string(table[k].second);
  return out;
}

/// Axes by letter (0 x, 1 y, 2 z).
inline constexpr NameTable<int, 3> kAxisNames = {{{0, "x"}, {1, "y"}, {2, "z"}}};

/// The value named `name`, or InputError(file, field, name, "expected <names>") (exit 2).
template <class E, std::size_t N>
E parse_name(const NameTable<E, N>& table, const std::string& file, const std::string& field, const std::string& name) {
  if (const auto v = value_of(table, name)) return *v;
  throw InputError(file, field, name, "expected " + names_of(table));
}

}  // namespace tomodem
