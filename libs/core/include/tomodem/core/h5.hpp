#pragma once
// A thin HDF5 file wrapper that keeps the HDF5 headers out of every other translation unit.
// Paths are absolute inside the file ("/particles/radius"); parent groups are created on write.
// Errors while reading name the file and the dataset (InputError); write errors are RuntimeFailure.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace tomodem::h5 {

class File {
 public:
  enum class Mode { read, create };  ///< create truncates an existing file
  File(const std::string& path, Mode mode);
  ~File();
  File(File&&) noexcept;
  File& operator=(File&&) noexcept;
  File(const File&) = delete;
  File& operator=(const File&) = delete;

  const std::string& path() const;
  /// Flushes and closes the file now, checking every step: a write that HDF5 could only finish
  /// here (its metadata cache, a full disk, a file-size limit) is a RuntimeFailure naming the
  /// file and the reason. Writers call it before renaming a temporary onto the real name; the
  /// destructor closes silently. Nothing happens when the file is already closed.
  void close();
  bool exists(const std::string& object) const;  ///< a group or dataset
  std::vector<std::string> children(const std::string& group) const;  ///< names, sorted
  /// The shape of a dataset (InputError when missing); {} for a scalar dataset.
  std::vector<std::size_t> shape(const std::string& dataset) const;

  /// Datasets: `dims` gives the shape (row-major); empty dims = 1-D of data.size().
  /// `units` becomes a string attribute "units" on the dataset when not empty.
  void write(const std::string& dataset, const std::vector<double>& data, std::vector<std::size_t> dims = {},
             const std::string& units = "");
  void write(const std::string& dataset, const std::vector<int32_t>& data, std::vector<std::size_t> dims = {});
  void write(const std::string& dataset, const std::vector<int64_t>& data, std::vector<std::size_t> dims = {});
  void write(const std::string& dataset, const std::vector<uint8_t>& data, std::vector<std::size_t> dims = {});

  /// Removes a dataset or group (and everything below it); nothing happens when absent.
  /// The space is not reclaimed inside the file (HDF5 limitation); fine for small metadata.
  void remove(const std::string& object);

  /// Reads convert from any stored numeric type; `dims` (if given) receives the shape. A dataset
  /// that would need more memory than the machine has (a corrupt or hostile shape) is refused
  /// before anything is allocated (InputError naming the dataset, with need vs have).
  std::vector<double> read_double(const std::string& dataset, std::vector<std::size_t>* dims = nullptr) const;
  std::vector<int32_t> read_int32(const std::string& dataset, std::vector<std::size_t>* dims = nullptr) const;
  std::vector<int64_t> read_int64(const std::string& dataset, std::vector<std::size_t>* dims = nullptr) const;
  std::vector<uint8_t> read_uint8(const std::string& dataset, std::vector<std::size_t>* dims = nullptr) const;

  /// Attributes on a group or dataset ("/" for the root). Setting an attribute on a missing
  /// object creates it as a group; setting an existing attribute replaces it. Strings are
  /// stored as variable-length UTF-8; reading accepts fixed-length strings too.
  void set_attr(const std::string& object, const std::string& name, const std::string& value);
  void set_attr(const std::string& object, const std::string& name, double value);
  void set_attr(const std::string& object, const std::string& name, const std::vector<double>& value);
  /// An integer attribute (stored as int64); attr_int also accepts a float holding an integer.
  void set_attr_int(const std::string& object, const std::string& name, int64_t value);
  bool has_attr(const std::string& object, const std::string& name) const;
  std::vector<std::string> attr_names(const std::string& object) const;  ///< sorted
  std::string attr_string(const std::string& object, const std::string& name) const;
  double attr_double(const std::string& object, const std::string& name) const;
  std::vector<double> attr_doubles(const std::string& object, const std::string& name) const;
  int64_t attr_int(const std::string& object, const std::string& name) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tomodem::h5
