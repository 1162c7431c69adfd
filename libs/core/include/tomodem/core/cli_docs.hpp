#pragma once
// Man pages (troff) and bash completion generated from a tool's own CLI11 App, so neither can
// drift from the options the tool accepts (docs/cli.md, "Installing"). cli::parse answers
// `TOOL --help-man` and `TOOL --help-completion` with them; the install step writes their output to
// share/man/man1/TOOL.1 and share/bash-completion/completions/TOOL. Header-only like CLI11.
#include <CLI/CLI.hpp>

#include <sstream>
#include <string>
#include <vector>

namespace tomodem::cli {

namespace docs_detail {

/// Text as troff reads it literally: backslashes escaped, '-' as \- (a hyphen, not a dash), and a
/// line that starts with '.' or '\'' guarded (it would be a request).
inline std::string troff(const std::string& text) {
  std::string out;
  bool line_start = true;
  for (char c : text) {
    if (line_start && (c == '.' || c == '\'')) out += "\\&";
    if (c == '\\') out += "\\e";
    else if (c == '-') out += "\\-";
    else out += c;
    line_start = c == '\n';
  }
  return out;
}

/// The options --help shows (a hidden option has an empty group), the help flag included.
inline std::vector<const CLI::Option*> shown_options(const CLI::App& app) {
  std::vector<const CLI::Option*> out;
  for (const CLI::Option* o : app.get_options())
    if (!o->get_group().empty()) out.push_back(o);
  return out;
}

inline std::vector<const CLI::App*> shown_subcommands(const CLI::App& app) {
  return app.get_subcommands([](const CLI::App* s) { return !s->get_group().empty(); });
}

/// The value words of a choice option ("auto|tiff|mha" as add_choice sets the type name); none otherwise.
inline std::vector<std::string> choices(const CLI::Option* o) {
  const std::string t = o->get_type_name();
  std::vector<std::string> out;
  if (t.find('|') == std::string::npos || t.find(' ') != std::string::npos) return out;
  std::stringstream s(t);
  for (std::string w; std::getline(s, w, '|');)
    if (!w.empty()) out.push_back(w);
  return out;
}

/// ".TP" items of one App's options: names, value type, description and default.
inline void option_items(std::ostream& os, const CLI::App& app) {
  for (const CLI::Option* o : shown_options(app)) {
    os << ".TP\n";
    if (o->nonpositional()) {
      std::string names;
      for (const auto& s : o->get_snames()) names += (names.empty() ? "" : ", ") + std::string("\\fB\\-") + s + "\\fR";
      for (const auto& l : o->get_lnames()) names += (names.empty() ? "" : ", ") + std::string("\\fB\\-\\-") + troff(l) + "\\fR";
      os << names;
      if (o->get_type_size() != 0 && !o->get_type_name().empty()) os << " \\fI" << troff(o->get_type_name()) << "\\fR";
    } else {
      os << "\\fI" << troff(o->get_name()) << "\\fR";
    }
    os << "\n" << troff(o->get_description());
    if (o->get_required()) os << " (required)";
    if (!o->get_default_str().empty()) os << " (default: " << troff(o->get_default_str()) << ")";
    os << "\n";
  }
}

inline std::string upper(std::string s) {
  for (auto& c : s) c = char(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace docs_detail

/// The tool's manual page in troff (man(7)): name, synopsis, description, every option --help shows
/// (with its default), each subcommand's options, and the exit codes of docs/cli.md.
inline std::string man_page(const CLI::App& app, const std::string& tool, const std::string& version) {
  using namespace docs_detail;
  std::ostringstream os;
  std::string summary = app.get_description();
  if (summary.rfind(tool + ": ", 0) == 0) summary = summary.substr(tool.size() + 2);
  const std::string first_line = summary.substr(0, summary.find('\n'));
  os << ".TH " << upper(tool) << " 1 \"\" \"" << troff(version) << "\" \"tomodem manual\"\n"
     << ".SH NAME\n" << troff(tool) << " \\- " << troff(first_line) << "\n"
     << ".SH SYNOPSIS\n.B " << troff(tool) << "\n";
  if (!shown_subcommands(app).empty()) os << "[\\fISUBCOMMAND\\fR] ";
  os << "[\\fIOPTIONS\\fR]";
  for (const CLI::Option* o : shown_options(app))
    if (!o->nonpositional()) os << (o->get_required() ? " \\fI" : " [\\fI") << troff(o->get_name()) << (o->get_required() ? "\\fR" : "\\fR]");
  os << "\n.SH DESCRIPTION\n" << troff(summary) << "\n.SH OPTIONS\n";
  option_items(os, app);
  const auto subs = shown_subcommands(app);
  if (!subs.empty()) {
    os << ".SH SUBCOMMANDS\n";
    for (const CLI::App* s : subs) {
      os << ".SS " << troff(s->get_name()) << "\n" << troff(s->get_description()) << "\n";
      option_items(os, *s);
      for (const CLI::App* s2 : shown_subcommands(*s)) {
        os << ".SS " << troff(s->get_name() + " " + s2->get_name()) << "\n" << troff(s2->get_description()) << "\n";
        option_items(os, *s2);
      }
    }
  }
  os << ".SH EXIT STATUS\n"
        ".TP\n0\nsuccess (also after \\-\\-help and \\-\\-version)\n"
        ".TP\n1\nfailure (a file that cannot be written, an internal error)\n"
        ".TP\n2\nbad input: the message names the file, field or option and the value\n"
        ".TP\n3\nnumerical failure (an unstable or diverging computation)\n"
        ".SH SEE ALSO\n\\fBtomodem\\fR(1); docs/cli.md in the tomodem sources\n";
  return os.str();
}

/// A bash completion script for `tool`: its options (and subcommands), the value words of choice
/// options, file names elsewhere.
inline std::string bash_completion(const CLI::App& app, const std::string& tool) {
  using namespace docs_detail;
  std::string fn = "_" + tool;
  for (auto& c : fn)
    if (c == '-') c = '_';
  std::string words, subwords, cases;
  const auto add_app = [&](const CLI::App& a) {
    for (const CLI::Option* o : shown_options(a)) {
      if (!o->nonpositional()) continue;
      for (const auto& s : o->get_snames()) words += " -" + s;
      for (const auto& l : o->get_lnames()) words += " --" + l;
      const auto ch = choices(o);
      if (ch.empty() || o->get_lnames().empty()) continue;
      std::string list;
      for (const auto& w : ch) list += (list.empty() ? "" : " ") + w;
      cases += "    --" + o->get_lnames().front() + ") COMPREPLY=($(compgen -W \"" + list + "\" -- \"$cur\")); return ;;\n";
    }
  };
  add_app(app);
  for (const CLI::App* s : shown_subcommands(app)) {
    subwords += " " + s->get_name();
    add_app(*s);
    for (const CLI::App* s2 : shown_subcommands(*s)) {
      subwords += " " + s2->get_name();
      add_app(*s2);
    }
  }
  std::ostringstream os;
  os << "# bash completion for " << tool << " (generated by " << tool << " --help-completion)\n"
     << fn << "() {\n"
     << "  local cur=\"${COMP_WORDS[COMP_CWORD]}\" prev=\"${COMP_WORDS[COMP_CWORD-1]}\"\n"
     << "  case \"$prev\" in\n" << cases << "  esac\n"
     << "  if [[ \"$cur\" == -* ]]; then\n"
     << "    COMPREPLY=($(compgen -W \"" << words.substr(words.empty() ? 0 : 1) << "\" -- \"$cur\"))\n"
     << "  else\n"
     << "    COMPREPLY=(" << (subwords.empty() ? "" : "$(compgen -W \"" + subwords.substr(1) + "\" -- \"$cur\") ")
     << "$(compgen -f -- \"$cur\"))\n"
     << "  fi\n"
     << "}\n"
     << "complete -o filenames -F " << fn << " " << tool << "\n";
  return os.str();
}

}  // namespace tomodem::cli
