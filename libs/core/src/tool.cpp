#include "tomodem/core/tool.hpp"

#include <iostream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"

namespace tomodem {

namespace {
bool g_quiet = false;
std::string g_tool = "tomodem";
}  // namespace

std::string version_string() {
  return std::string("tomodem ") + TOMODEM_VERSION + " (git " + TOMODEM_GIT_HASH + ")";
}

void set_quiet(bool q) { g_quiet = q; }
bool quiet() { return g_quiet; }
void info(const std::string& m) {
  if (!g_quiet) std::cerr << g_tool << ": " << m << '\n';
}
void warn(const std::string& m) { std::cerr << g_tool << ": warning: " << m << '\n'; }

int run_tool(const std::string& tool_name, const std::function<int()>& body) {
  g_tool = tool_name;
  install_cleanup_handlers();
  // However the body ends, a temporary it did not commit must not stay behind.
  struct Cleanup {
    ~Cleanup() { remove_registered_temporaries(); }
  } cleanup;
  try {
    return body();
  } catch (const InputError& e) {
    std::cerr << tool_name << ": error: " << e.what() << '\n';
    return exit_code::bad_input;
  } catch (const NumericalError& e) {
    std::cerr << tool_name << ": numerical failure: " << e.what() << '\n';
    return exit_code::numerical;
  } catch (const std::exception& e) {
    std::cerr << tool_name << ": failure: " << e.what() << '\n';
    return exit_code::failure;
  }
}

}  // namespace tomodem
