#pragma once
// Outputs are written under a temporary name and renamed at the end, so a failed or killed
// run never leaves a half-written file under the real name. Temporaries are registered: a tool
// stopped by SIGINT or SIGTERM removes them (run_tool installs the handlers). Inside a tool's run
// the renames wait for the run's end (run_tool): a run that fails after writing some of its
// outputs leaves none of them, and the old files stay as they were.
#include <cstdint>
#include <string>
#include <vector>

namespace tomodem {

/// One rank writes (docs/scaling.md, "Outputs on several ranks"). A tool (named by run_tool)
/// started by mpirun or srun on several ranks computes the same results on every rank, and only
/// rank 0 prints and writes: on the others this is false, and their info, warnings, progress and
/// summary are not printed and their outputs not written (write_text_atomic returns at once,
/// HDF5 files are built in memory and dropped, temporaries are never created, commit_output
/// renames nothing). Programs that are not tools (tests under mpirun) write on every rank.
bool writes_outputs();

/// The temporary name used for `final_path` (same folder, so rename is atomic). Registered for
/// removal on SIGINT/SIGTERM until commit_output or discard_output.
std::string temporary_path(const std::string& final_path);
/// When commit_output renames: with the run (the default) waits for commit_pending_outputs while
/// commits are deferred (a tool's run, run_tool); now renames at once (a checkpoint, which must
/// survive the run that writes it).
enum class Commit { with_run, now };
/// Renames the temporary file onto `final_path` (RuntimeFailure on error; the temporary is removed).
void commit_output(const std::string& final_path, Commit when = Commit::with_run);
/// From here on commit_output(…, Commit::with_run) only records the output; run_tool turns this
/// on for a tool's body.
void defer_commits();
/// Renames every recorded output onto its name, in the order they were committed, and stops
/// deferring. If one fails, the temporaries of the others not yet renamed are removed and
/// RuntimeFailure names the file.
void commit_pending_outputs();
/// Removes the temporaries of every recorded output and stops deferring (a run that failed).
void discard_pending_outputs();
/// Removes the temporary of `final_path`, if any (after a failed write).
void discard_output(const std::string& final_path);
/// Writes `text` to `path` atomically: every write, the flush to disk and the close are checked;
/// on any error the temporary is removed, the old file stays as it was, and RuntimeFailure names
/// the file and the reason (a full disk says so).
void write_text_atomic(const std::string& path, const std::string& text);
/// Removes every registered temporary now (what the signal handlers do; async-signal-safe).
void remove_registered_temporaries();
/// Installs SIGINT/SIGTERM handlers that remove the registered temporaries, then let the signal
/// end the process as it would have (exit status 128 + signal).
void install_cleanup_handlers();

/// Refuses (InputError, exit 2) an output that names an input: the same file, by path or by
/// identity (hard links, symbolic links, "./x" against "x"). `option` is how the user named the
/// output ("-o", "--json", "output.packing"); inputs are the files the tool reads. When
/// `output_is_folder`, an output folder that contains an input, or equals one, is refused too.
void refuse_output_over_input(const std::string& output, const std::string& option,
                              const std::vector<std::string>& inputs, bool output_is_folder = false);
/// An output as the user named it: the option ("--json") and the path.
struct OutputName {
  std::string option, path;
};
/// Checks every output before any work: refuses one that names an input (as
/// refuse_output_over_input), an existing folder, a file in a folder that does not exist, and two
/// outputs that name one file. "" and "-" (stdout) are not files and pass.
void check_outputs(const std::vector<std::string>& inputs, const std::vector<OutputName>& outputs);
/// "out.xdmf" for "out.h5": the sidecar the HDF5 writers add beside a file.
std::string xdmf_sidecar_of(const std::string& path);

/// Refuses (InputError) an output path that leaves `folder` (absolute, or with "..").
void refuse_output_outside(const std::string& path, const std::string& folder, const std::string& file,
                           const std::string& field);

/// The memory this process may use: the smaller of physical memory and the cgroup limit.
std::uint64_t usable_memory_bytes();
/// Refuses (InputError, exit 2) a request that would need more memory than usable_memory_bytes(),
/// before anything is allocated: the message gives what it would need and what the machine has.
/// `what` says what is requested ("10^12 particles").
void check_memory_request(double bytes, const std::string& file, const std::string& field,
                          const std::string& value, const std::string& what);
/// "1.5 GB" style text for byte counts in messages.
std::string bytes_text(double bytes);

/// The whole text of an input file (a scene, a config): InputError naming it when it is missing,
/// a folder or unreadable. `what` says what the file is ("scene file").
std::string read_input_text(const std::string& path, const std::string& what);

/// A CSV time series with a header that carries the unit of each column ("time_s" style names).
std::string csv_table(const std::vector<std::string>& columns, const std::vector<std::vector<double>>& rows);

/// Hex content hash of a file (for provenance and pipeline staleness).
std::string file_hash(const std::string& path);

/// Current time as ISO 8601 UTC.
std::string utc_now();

/// `s` with & < > " ' as XML/HTML entities (XDMF sidecars, the HTML report).
std::string xml_escape(const std::string& s);

}  // namespace tomodem
