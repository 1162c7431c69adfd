#pragma once
// Outputs are written under a temporary name and renamed at the end, so a failed or killed
// run never leaves a half-written file under the real name.
#include <string>
#include <vector>

namespace tomodem {

/// The temporary name used for `final_path` (same folder, so rename is atomic).
std::string temporary_path(const std::string& final_path);
/// Renames the temporary file onto `final_path` (RuntimeFailure on error).
void commit_output(const std::string& final_path);
/// Writes `text` to `path` atomically.
void write_text_atomic(const std::string& path, const std::string& text);

/// A CSV time series with a header that carries the unit of each column ("time_s" style names).
std::string csv_table(const std::vector<std::string>& columns, const std::vector<std::vector<double>>& rows);

/// Hex content hash of a file (for provenance and pipeline staleness).
std::string file_hash(const std::string& path);

/// Current time as ISO 8601 UTC.
std::string utc_now();

}  // namespace tomodem
