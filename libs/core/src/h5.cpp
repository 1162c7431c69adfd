// HDF5 C API behind a small pimpl (h5.hpp). The only translation unit that includes hdf5.h.
//
// Error policy: HDF5's automatic error printing is switched off (per thread: the Debian build is
// thread-safe and keeps one error stack per thread); failures become InputError on read and
// RuntimeFailure on write, carrying the innermost HDF5 message.
#include "tomodem/core/h5.hpp"

#include <hdf5.h>

#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <functional>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"

namespace tomodem::h5 {

namespace {

// HDF5 closes every file still open again in its atexit handler. After a close that failed (a
// full disk, a file-size limit) HDF5 1.10 crashes there (SIGSEGV in H5F__close_cb), which turned
// an honest "cannot write" (exit 1) into a signal. Every File closes itself (close() or its
// destructor), so the handler is not needed; H5dont_atexit only works before the library starts,
// hence a static initializer.
const bool kNoAtexitHandler = [] {
  H5dont_atexit();
  return true;
}();

// HDF5 keeps the automatic printer per thread in thread-safe builds, so install it once per thread.
void silence() {
  thread_local bool done = false;
  if (!done) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    done = true;
  }
}

// The innermost (most specific) message on the current HDF5 error stack, for our own messages.
std::string last_error() {
  std::string msg;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned n, const H5E_error2_t* e, void* out) -> herr_t {
        if (n == 0 && e->desc) *static_cast<std::string*>(out) = e->desc;
        return 0;
      },
      &msg);
  // The file drivers' messages carry the time, a buffer address and byte counts over several
  // lines; keep what failed and the system's reason ("file write failed: No space left on device").
  const auto k = msg.find("error message = '");
  if (k != std::string::npos) {
    const auto end = msg.find('\'', k + 17);
    msg = msg.substr(0, msg.find(':')) + ": " + msg.substr(k + 17, end == std::string::npos ? end : end - (k + 17));
  }
  return msg.empty() ? "HDF5 error" : "HDF5: " + msg;
}

// Closes an HDF5 handle on scope exit.
struct Handle {
  hid_t id = H5I_INVALID_HID;
  herr_t (*close)(hid_t) = nullptr;
  Handle() = default;
  Handle(hid_t i, herr_t (*c)(hid_t)) : id(i), close(c) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() {
    if (id >= 0 && close) close(id);
  }
  bool ok() const { return id >= 0; }
  operator hid_t() const { return id; }
};

std::string shape_text(const std::vector<std::size_t>& dims) {
  std::string s = "(";
  for (std::size_t k = 0; k < dims.size(); ++k) s += (k ? ", " : "") + std::to_string(dims[k]);
  return s + ")";
}

// "particles/radius" and "/particles/radius" name the same object.
std::string absolute(const std::string& p) { return (p.empty() || p[0] != '/') ? "/" + p : p; }

// Why `path` cannot be opened for reading ("" when it is a regular file).
std::string not_a_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return std::string("cannot open: ") + std::strerror(errno);
  if (S_ISDIR(st.st_mode)) return "is a directory, not an HDF5 file";
  if (!S_ISREG(st.st_mode)) return "not a regular file (an HDF5 file is expected)";
  if (st.st_size == 0) return "empty file (0 bytes), not an HDF5 file";
  return "";
}

// The HDF5 memory type for each element type we expose.
template <class T> hid_t native();
template <> hid_t native<double>() { return H5T_NATIVE_DOUBLE; }
template <> hid_t native<int32_t>() { return H5T_NATIVE_INT32; }
template <> hid_t native<int64_t>() { return H5T_NATIVE_INT64; }
template <> hid_t native<uint8_t>() { return H5T_NATIVE_UINT8; }
// Fixed little-endian file types, so files are identical across machines.
template <class T> hid_t stored();
template <> hid_t stored<double>() { return H5T_IEEE_F64LE; }
template <> hid_t stored<int32_t>() { return H5T_STD_I32LE; }
template <> hid_t stored<int64_t>() { return H5T_STD_I64LE; }
template <> hid_t stored<uint8_t>() { return H5T_STD_U8LE; }
template <class T> const char* type_name();
template <> const char* type_name<double>() { return "float64"; }
template <> const char* type_name<int32_t>() { return "int32"; }
template <> const char* type_name<int64_t>() { return "int64"; }
template <> const char* type_name<uint8_t>() { return "uint8"; }

// Conversion exceptions during reads: out of range, fractional or NaN values must not be clamped
// or truncated silently into integers. Loss of precision (int64 -> double) is accepted.
H5T_conv_ret_t strict_conversion(H5T_conv_except_t except, hid_t, hid_t, void*, void*, void*) {
  return except == H5T_CONV_EXCEPT_PRECISION ? H5T_CONV_UNHANDLED : H5T_CONV_ABORT;
}

bool numeric_class(H5T_class_t c) { return c == H5T_INTEGER || c == H5T_FLOAT; }

// ---------------------------------------------------------------- variable-length strings
//
// Variable-length strings (the tool, parameters and material names, written by every tomodem
// writer) live in the file's global heap. libhdf5 1.10 dies (SIGSEGV in H5HG_read) or loops for
// ever (H5C_protect) on a corrupt global-heap reference, and nothing before the read can tell.
// So a file opened for reading has every variable-length string attribute read once by a child
// process first. The child names each attribute on a pipe before it reads it; when the child
// dies, or names nothing new for kQuietSeconds, the file is refused naming that attribute.
constexpr int kQuietSeconds = 3;

void say(int fd, const std::string& s) {
  const std::string line = s + "\n";
  if (::write(fd, line.data(), line.size()) < 0) ::_exit(3);
}

herr_t read_string_attr(hid_t loc, const char* name, const H5A_info_t*, void* data) {
  const auto& [fd, object] = *static_cast<std::pair<int, std::string>*>(data);
  const hid_t attr = H5Aopen(loc, name, H5P_DEFAULT);
  if (attr < 0) return 0;
  const hid_t type = H5Aget_type(attr);
  if (type >= 0 && H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) > 0) {
    say(fd, object + "@" + name);
    const hid_t space = H5Aget_space(attr);
    const hssize_t n = H5Sget_simple_extent_npoints(space);
    if (n > 0 && n < (1 << 20)) {
      const hid_t mem = H5Tcopy(H5T_C_S1);
      H5Tset_size(mem, H5T_VARIABLE);
      H5Tset_cset(mem, H5Tget_cset(type));
      std::vector<char*> p(static_cast<std::size_t>(n), nullptr);
      if (H5Aread(attr, mem, p.data()) >= 0) H5Dvlen_reclaim(mem, space, H5P_DEFAULT, p.data());
      H5Tclose(mem);
    }
    H5Sclose(space);
  }
  if (type >= 0) H5Tclose(type);
  H5Aclose(attr);
  return 0;
}

void read_string_attrs_of(hid_t file, const std::string& object, int fd) {
  const hid_t obj = H5Oopen(file, object.c_str(), H5P_DEFAULT);
  if (obj < 0) return;
  std::pair<int, std::string> data{fd, object};
  hsize_t idx = 0;
  H5Aiterate2(obj, H5_INDEX_NAME, H5_ITER_NATIVE, &idx, read_string_attr, &data);
  H5Oclose(obj);
}

herr_t visit_link(hid_t, const char* name, const H5L_info_t* info, void* data) {
  if (info->type == H5L_TYPE_HARD) {
    const auto& [file, fd] = *static_cast<std::pair<hid_t, int>*>(data);
    read_string_attrs_of(file, "/" + std::string(name), fd);
  }
  return 0;
}

void check_strings_in_child(hid_t file, const std::string& path) {
  int fds[2];
  if (::pipe(fds) != 0) return;  // cannot check: read as before
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    return;
  }
  if (pid == 0) {  // the child: read them all, then leave without running any exit handler
    ::close(fds[0]);
    ::signal(SIGPIPE, SIG_DFL);
    read_string_attrs_of(file, "/", fds[1]);
    std::pair<hid_t, int> data{file, fds[1]};
    H5Lvisit(file, H5_INDEX_NAME, H5_ITER_NATIVE, visit_link, &data);
    say(fds[1], "");
    ::_exit(0);
  }
  ::close(fds[1]);
  std::string said;
  bool hung = false;
  for (;;) {
    pollfd p{fds[0], POLLIN, 0};
    const int r = ::poll(&p, 1, kQuietSeconds * 1000);
    if (r == 0) {
      hung = true;
      ::kill(pid, SIGKILL);
      break;
    }
    if (r < 0) {
      if (errno == EINTR) continue;
      break;
    }
    char buf[4096];
    const ssize_t n = ::read(fds[0], buf, sizeof buf);
    if (n <= 0) break;
    said.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!hung && WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  // The attribute named last is the one being read when the child died or stalled.
  std::string last;
  if (!said.empty()) {
    const auto end = said.back() == '\n' ? said.size() - 1 : said.size();
    const auto start = said.rfind('\n', end == 0 ? 0 : end - 1);
    last = said.substr(start == std::string::npos ? 0 : start + 1, end - (start == std::string::npos ? 0 : start + 1));
  }
  if (hung)
    throw InputError(path, last, "", "corrupt file: the HDF5 library does not finish reading this string attribute");
  if (WIFSIGNALED(status))
    throw InputError(path, last, "",
                     std::string("corrupt file: reading this string attribute crashes the HDF5 library (") +
                         ::strsignal(WTERMSIG(status)) + ")");
  // Any other end of the child (no pipe, a write error): no verdict, read as before.
}

}  // namespace

struct File::Impl {
  hid_t file = H5I_INVALID_HID;
  std::string path;
  bool writable = false;

  [[noreturn]] void read_error(const std::string& object, const std::string& value, const std::string& why) const {
    throw InputError(path, object, value, why);
  }
  [[noreturn]] void write_error(const std::string& object, const std::string& why) const {
    throw RuntimeFailure(path + ": cannot write '" + object + "': " + why);
  }

  // True when every prefix of `p` is a link that resolves (H5Lexists fails on a missing parent).
  bool exists(const std::string& p) const {
    const std::string a = absolute(p);
    if (a == "/") return true;
    std::size_t pos = 1;
    while (true) {
      const std::size_t next = a.find('/', pos);
      const std::string prefix = a.substr(0, next);
      if (H5Lexists(file, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
      if (H5Oexists_by_name(file, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
      if (next == std::string::npos || next + 1 >= a.size()) return true;
      pos = next + 1;
    }
  }

  // Opens a group or dataset for attributes; creates missing groups when `create` is set.
  hid_t open_object(const std::string& object, bool create) const {
    const std::string a = absolute(object);
    if (!exists(a)) {
      if (!create) read_error(a, "", "no such group or dataset");
      Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
      H5Pset_create_intermediate_group(lcpl, 1);
      Handle g(H5Gcreate2(file, a.c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
      if (!g.ok()) write_error(a, last_error());
    }
    const hid_t o = H5Oopen(file, a.c_str(), H5P_DEFAULT);
    if (o < 0) {
      if (create) write_error(a, last_error());
      read_error(a, "", "cannot open: " + last_error());
    }
    return o;
  }

  template <class T>
  void write(const std::string& dataset, const std::vector<T>& data, std::vector<std::size_t> dims,
             const std::string& units) {
    silence();
    const std::string a = absolute(dataset);
    if (!writable) write_error(a, "file is open for reading");
    if (a == "/" || a.back() == '/') write_error(a, "not a dataset path");
    if (dims.empty()) dims = {data.size()};
    std::size_t count = 1;
    for (auto d : dims) count *= d;
    if (count != data.size())
      write_error(a, "shape " + shape_text(dims) + " does not hold " + std::to_string(data.size()) + " values");
    // Rewriting replaces the dataset (possibly with another shape or type).
    if (exists(a) && H5Ldelete(file, a.c_str(), H5P_DEFAULT) < 0) write_error(a, last_error());
    std::vector<hsize_t> hd(dims.begin(), dims.end());
    Handle space(H5Screate_simple(static_cast<int>(hd.size()), hd.data(), nullptr), H5Sclose);
    Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
    H5Pset_create_intermediate_group(lcpl, 1);
    Handle ds(H5Dcreate2(file, a.c_str(), stored<T>(), space, lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
    if (!space.ok() || !ds.ok()) write_error(a, last_error());
    if (!data.empty() && H5Dwrite(ds, native<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) < 0)
      write_error(a, last_error());
    if (!units.empty()) set_string_attr(ds, a, "units", units);
  }

  template <class T>
  std::vector<T> read(const std::string& dataset, std::vector<std::size_t>* dims_out) const {
    silence();
    const std::string a = absolute(dataset);
    if (!exists(a)) read_error(a, "", "missing dataset");
    {  // H5Iget_type rather than H5Oget_info_by_name, whose signature changed in HDF5 1.12
      Handle obj(H5Oopen(file, a.c_str(), H5P_DEFAULT), H5Oclose);
      if (obj.ok() && H5Iget_type(obj) != H5I_DATASET) read_error(a, "", "is a group, not a dataset");
    }
    Handle ds(H5Dopen2(file, a.c_str(), H5P_DEFAULT), H5Dclose);
    if (!ds.ok()) read_error(a, "", "cannot open dataset: " + last_error());
    Handle type(H5Dget_type(ds), H5Tclose);
    if (!numeric_class(H5Tget_class(type))) read_error(a, "", "dataset is not numeric");
    Handle space(H5Dget_space(ds), H5Sclose);
    const int rank = H5Sget_simple_extent_ndims(space);
    if (rank < 0) read_error(a, "", "cannot read the shape: " + last_error());
    std::vector<hsize_t> hd(static_cast<std::size_t>(rank));
    H5Sget_simple_extent_dims(space, hd.data(), nullptr);
    // The shape comes from the file: check what it would take before allocating (a corrupt or
    // hostile header claiming 10^12 rows must not end in bad_alloc or the OOM killer).
    double want = 1;
    for (auto d : hd) want *= static_cast<double>(d);
    check_memory_request(want * sizeof(T), path, a, shape_text(std::vector<std::size_t>(hd.begin(), hd.end())),
                         shape_text(std::vector<std::size_t>(hd.begin(), hd.end())) + " values of " + type_name<T>());
    std::size_t count = 1;
    for (auto d : hd) count *= static_cast<std::size_t>(d);
    std::vector<T> out(count);
    if (count > 0) {
      Handle xfer(H5Pcreate(H5P_DATASET_XFER), H5Pclose);
      H5Pset_type_conv_cb(xfer, strict_conversion, nullptr);
      if (H5Dread(ds, native<T>(), H5S_ALL, H5S_ALL, xfer, out.data()) < 0)
        read_error(a, "", std::string("cannot read as ") + type_name<T>() +
                              " (values out of range, fractional or NaN?): " + last_error());
    }
    if (dims_out) dims_out->assign(hd.begin(), hd.end());
    return out;
  }

  void set_string_attr(hid_t obj, const std::string& object, const std::string& name, const std::string& value) const {
    // Variable-length UTF-8: h5py reads it as str, and the text has no 64 KiB attribute limit
    // (it lives in the global heap).
    Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(type, H5T_VARIABLE);
    H5Tset_cset(type, H5T_CSET_UTF8);
    Handle space(H5Screate(H5S_SCALAR), H5Sclose);
    replace_attr(obj, object, name, type, space, [&](hid_t attr) {
      const char* p = value.c_str();
      return H5Awrite(attr, type, &p);
    });
  }

  void replace_attr(hid_t obj, const std::string& object, const std::string& name, hid_t type, hid_t space,
                    const std::function<herr_t(hid_t)>& write_fn) const {
    if (!writable) write_error(object + "@" + name, "file is open for reading");
    if (H5Aexists(obj, name.c_str()) > 0 && H5Adelete(obj, name.c_str()) < 0)
      write_error(object + "@" + name, last_error());
    Handle attr(H5Acreate2(obj, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    if (!attr.ok() || write_fn(attr) < 0) write_error(object + "@" + name, last_error());
  }

  // Opens attribute `name` of `object` or throws an InputError naming both.
  hid_t open_attr(const std::string& object, const std::string& name, Handle& obj) const {
    obj.id = open_object(object, false);
    obj.close = H5Oclose;
    if (H5Aexists(obj, name.c_str()) <= 0) read_error(absolute(object) + "@" + name, "", "missing attribute");
    const hid_t attr = H5Aopen(obj, name.c_str(), H5P_DEFAULT);
    if (attr < 0) read_error(absolute(object) + "@" + name, "", "cannot open attribute: " + last_error());
    return attr;
  }
};

File::File(const std::string& path, Mode mode) : impl_(std::make_unique<Impl>()) {
  silence();
  impl_->path = path;
  if (mode == Mode::read) {
    if (const std::string why = not_a_file(path); !why.empty()) throw InputError(path, "", "", why);
    if (H5Fis_hdf5(path.c_str()) <= 0)
      throw InputError(path, "", "", "not an HDF5 file (no HDF5 signature: a text file, random bytes or cut before it)");
    impl_->file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    if (impl_->file < 0) {
      const std::string why = last_error();
      throw InputError(path, "", "",
                       why.find("truncated file") != std::string::npos
                           ? "the file is cut short (an interrupted copy or write?): " + why
                           : "cannot open: " + why);
    }
    try {
      check_strings_in_child(impl_->file, path);
    } catch (...) {
      H5Fclose(impl_->file);
      impl_->file = H5I_INVALID_HID;
      throw;
    }
  } else {
    // A silent rank (output.hpp, writes_outputs) builds the file in memory and drops it at close.
    Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    if (!writes_outputs()) H5Pset_fapl_core(fapl, 1 << 20, false);
    impl_->file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    if (impl_->file < 0) throw RuntimeFailure(path + ": cannot create HDF5 file: " + last_error());
    impl_->writable = true;
  }
}

File::~File() {
  if (impl_ && impl_->file >= 0) {
    silence();
    H5Fclose(impl_->file);
  }
}

File::File(File&&) noexcept = default;
File& File::operator=(File&&) noexcept = default;

const std::string& File::path() const { return impl_->path; }

void File::close() {
  if (!impl_ || impl_->file < 0) return;
  silence();
  const hid_t id = impl_->file;
  impl_->file = H5I_INVALID_HID;  // closed (or given up) either way: the destructor must not retry
  std::string why;
  if (impl_->writable && H5Fflush(id, H5F_SCOPE_LOCAL) < 0) why = last_error();
  if (H5Fclose(id) < 0 && why.empty()) why = last_error();
  if (!why.empty())
    throw RuntimeFailure(impl_->path + ": cannot " + (impl_->writable ? "finish writing" : "close") +
                         " the HDF5 file (disk full or a file-size limit?): " + why);
}

bool File::exists(const std::string& object) const {
  silence();
  return impl_->exists(object);
}

std::vector<std::string> File::children(const std::string& group) const {
  silence();
  const std::string a = absolute(group);
  if (!impl_->exists(a)) impl_->read_error(a, "", "missing group");
  Handle g(H5Gopen2(impl_->file, a.c_str(), H5P_DEFAULT), H5Gclose);
  if (!g.ok()) impl_->read_error(a, "", "not a group");
  std::vector<std::string> names;
  hsize_t idx = 0;
  H5Literate(
      g, H5_INDEX_NAME, H5_ITER_INC, &idx,
      [](hid_t, const char* name, const H5L_info_t*, void* out) -> herr_t {
        static_cast<std::vector<std::string>*>(out)->emplace_back(name);
        return 0;
      },
      &names);
  return names;
}

std::vector<std::size_t> File::shape(const std::string& dataset) const {
  silence();
  const std::string a = absolute(dataset);
  if (!impl_->exists(a)) impl_->read_error(a, "", "missing dataset");
  Handle ds(H5Dopen2(impl_->file, a.c_str(), H5P_DEFAULT), H5Dclose);
  if (!ds.ok()) impl_->read_error(a, "", "not a dataset");
  Handle space(H5Dget_space(ds), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space);
  std::vector<hsize_t> hd(static_cast<std::size_t>(std::max(rank, 0)));
  if (rank > 0) H5Sget_simple_extent_dims(space, hd.data(), nullptr);
  return {hd.begin(), hd.end()};
}

void File::write(const std::string& d, const std::vector<double>& v, std::vector<std::size_t> dims,
                 const std::string& units) {
  impl_->write(d, v, std::move(dims), units);
}
void File::write(const std::string& d, const std::vector<int32_t>& v, std::vector<std::size_t> dims) {
  impl_->write(d, v, std::move(dims), "");
}
void File::write(const std::string& d, const std::vector<int64_t>& v, std::vector<std::size_t> dims) {
  impl_->write(d, v, std::move(dims), "");
}
void File::write(const std::string& d, const std::vector<uint8_t>& v, std::vector<std::size_t> dims) {
  impl_->write(d, v, std::move(dims), "");
}

void File::remove(const std::string& object) {
  silence();
  const std::string a = absolute(object);
  if (!impl_->writable) impl_->write_error(a, "file is open for reading");
  if (a == "/") impl_->write_error(a, "cannot remove the root group");
  if (impl_->exists(a) && H5Ldelete(impl_->file, a.c_str(), H5P_DEFAULT) < 0) impl_->write_error(a, last_error());
}

std::vector<double> File::read_double(const std::string& d, std::vector<std::size_t>* dims) const {
  return impl_->read<double>(d, dims);
}
std::vector<int32_t> File::read_int32(const std::string& d, std::vector<std::size_t>* dims) const {
  return impl_->read<int32_t>(d, dims);
}
std::vector<int64_t> File::read_int64(const std::string& d, std::vector<std::size_t>* dims) const {
  return impl_->read<int64_t>(d, dims);
}
std::vector<uint8_t> File::read_uint8(const std::string& d, std::vector<std::size_t>* dims) const {
  return impl_->read<uint8_t>(d, dims);
}

void File::set_attr(const std::string& object, const std::string& name, const std::string& value) {
  silence();
  Handle obj(impl_->open_object(object, true), H5Oclose);
  impl_->set_string_attr(obj, absolute(object), name, value);
}

void File::set_attr(const std::string& object, const std::string& name, double value) {
  silence();
  Handle obj(impl_->open_object(object, true), H5Oclose);
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  impl_->replace_attr(obj, absolute(object), name, H5T_IEEE_F64LE, space,
                      [&](hid_t attr) { return H5Awrite(attr, H5T_NATIVE_DOUBLE, &value); });
}

void File::set_attr(const std::string& object, const std::string& name, const std::vector<double>& value) {
  silence();
  Handle obj(impl_->open_object(object, true), H5Oclose);
  const hsize_t n = value.size();
  // An empty vector becomes a null dataspace (a zero-length simple dataspace is not allowed here).
  Handle space(n ? H5Screate_simple(1, &n, nullptr) : H5Screate(H5S_NULL), H5Sclose);
  impl_->replace_attr(obj, absolute(object), name, H5T_IEEE_F64LE, space, [&](hid_t attr) -> herr_t {
    return n ? H5Awrite(attr, H5T_NATIVE_DOUBLE, value.data()) : 0;
  });
}

void File::set_attr_int(const std::string& object, const std::string& name, int64_t value) {
  silence();
  Handle obj(impl_->open_object(object, true), H5Oclose);
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  impl_->replace_attr(obj, absolute(object), name, H5T_STD_I64LE, space,
                      [&](hid_t attr) { return H5Awrite(attr, H5T_NATIVE_INT64, &value); });
}

bool File::has_attr(const std::string& object, const std::string& name) const {
  silence();
  if (!impl_->exists(object)) return false;
  Handle obj(impl_->open_object(object, false), H5Oclose);
  return H5Aexists(obj, name.c_str()) > 0;
}

std::vector<std::string> File::attr_names(const std::string& object) const {
  silence();
  Handle obj(impl_->open_object(object, false), H5Oclose);
  std::vector<std::string> names;
  hsize_t idx = 0;
  H5Aiterate2(
      obj, H5_INDEX_NAME, H5_ITER_INC, &idx,
      [](hid_t, const char* name, const H5A_info_t*, void* out) -> herr_t {
        static_cast<std::vector<std::string>*>(out)->emplace_back(name);
        return 0;
      },
      &names);
  return names;
}

std::string File::attr_string(const std::string& object, const std::string& name) const {
  silence();
  Handle obj;
  Handle attr(impl_->open_attr(object, name, obj), H5Aclose);
  const std::string where = absolute(object) + "@" + name;
  Handle type(H5Aget_type(attr), H5Tclose);
  if (H5Tget_class(type) != H5T_STRING) impl_->read_error(where, "", "attribute is not a string");
  Handle space(H5Aget_space(attr), H5Sclose);
  if (H5Sget_simple_extent_npoints(space) != 1) impl_->read_error(where, "", "expected a single string");
  if (H5Tis_variable_str(type) > 0) {
    Handle mem(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mem, H5T_VARIABLE);
    H5Tset_cset(mem, H5Tget_cset(type));
    char* p = nullptr;
    if (H5Aread(attr, mem, &p) < 0) impl_->read_error(where, "", "cannot read: " + last_error());
    std::string s = p ? p : "";
    H5free_memory(p);
    return s;
  }
  // Fixed-length strings (h5py's np.bytes_, other tools): read raw and drop the padding.
  const std::size_t size = H5Tget_size(type);
  std::string s(size, '\0');
  if (H5Aread(attr, type, s.data()) < 0) impl_->read_error(where, "", "cannot read: " + last_error());
  const auto end = s.find('\0');
  if (end != std::string::npos) s.resize(end);
  while (!s.empty() && s.back() == ' ') s.pop_back();  // H5T_STR_SPACEPAD
  return s;
}

std::vector<double> File::attr_doubles(const std::string& object, const std::string& name) const {
  silence();
  Handle obj;
  Handle attr(impl_->open_attr(object, name, obj), H5Aclose);
  const std::string where = absolute(object) + "@" + name;
  Handle type(H5Aget_type(attr), H5Tclose);
  if (!numeric_class(H5Tget_class(type))) impl_->read_error(where, "", "attribute is not numeric");
  Handle space(H5Aget_space(attr), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  std::vector<double> out(static_cast<std::size_t>(std::max<hssize_t>(n, 0)));
  if (!out.empty() && H5Aread(attr, H5T_NATIVE_DOUBLE, out.data()) < 0)
    impl_->read_error(where, "", "cannot read: " + last_error());
  return out;
}

double File::attr_double(const std::string& object, const std::string& name) const {
  const auto v = attr_doubles(object, name);
  if (v.size() != 1)
    throw InputError(impl_->path, absolute(object) + "@" + name, std::to_string(v.size()) + " values",
                     "expected a single number");
  return v[0];
}

int64_t File::attr_int(const std::string& object, const std::string& name) const {
  silence();
  Handle obj;
  Handle attr(impl_->open_attr(object, name, obj), H5Aclose);
  const std::string where = absolute(object) + "@" + name;
  Handle type(H5Aget_type(attr), H5Tclose);
  if (!numeric_class(H5Tget_class(type))) impl_->read_error(where, "", "attribute is not numeric");
  Handle space(H5Aget_space(attr), H5Sclose);
  if (H5Sget_simple_extent_npoints(space) != 1) impl_->read_error(where, "", "expected a single integer");
  // Read as double first so 1.5 is refused rather than truncated; exact for |v| < 2^53.
  double v = 0;
  if (H5Aread(attr, H5T_NATIVE_DOUBLE, &v) < 0) impl_->read_error(where, "", "cannot read: " + last_error());
  if (!std::isfinite(v) || std::fabs(v) >= 9.2e18 || v != std::trunc(v)) {
    std::ostringstream s;
    s << v;
    impl_->read_error(where, s.str(), "expected an integer");
  }
  if (H5Tget_class(type) == H5T_INTEGER) {  // reread exactly: large int64 values lose bits in a double
    int64_t i = 0;
    if (H5Aread(attr, H5T_NATIVE_INT64, &i) < 0) impl_->read_error(where, "", "cannot read: " + last_error());
    return i;
  }
  return static_cast<int64_t>(v);
}

}  // namespace tomodem::h5
