// Structure checks of TIFF, MetaImage and NIfTI files before they are read (file_checks.hpp).
#include "file_checks.hpp"

#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <vector>

#include "tomodem/core/error.hpp"

namespace fs = std::filesystem;

namespace tomodem::image::checks {
namespace {

std::string num(std::uint64_t x) { return std::to_string(x); }

std::uint64_t file_size_of(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(path, "", "", "is a folder, not a file");
  const auto s = fs::file_size(path, ec);
  if (ec) throw InputError(path, "", "", "cannot read the file: " + ec.message());
  return s;
}

// Random access reads that report whether the bytes exist.
struct Reader {
  std::ifstream in;
  std::uint64_t size = 0;
  bool big_endian = false;
  explicit Reader(const std::string& path) : in(path, std::ios::binary), size(file_size_of(path)) {
    if (!in) throw InputError(path, "", "", "cannot open the file for reading");
  }
  bool bytes(std::uint64_t off, std::size_t n, unsigned char* out) {
    if (off > size || n > size - off) return false;
    in.clear();
    in.seekg(static_cast<std::streamoff>(off));
    in.read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(n));
    return static_cast<std::size_t>(in.gcount()) == n;
  }
  // An unsigned integer of n bytes (1, 2, 4, 8) in the file's byte order.
  bool uint(std::uint64_t off, std::size_t n, std::uint64_t* v) {
    unsigned char b[8];
    if (!bytes(off, n, b)) return false;
    *v = 0;
    for (std::size_t i = 0; i < n; ++i) *v |= std::uint64_t(b[big_endian ? n - 1 - i : i]) << (8 * i);
    return true;
  }
};

std::size_t tiff_type_size(std::uint64_t type) {
  switch (type) {
    case 1: case 2: case 6: case 7: return 1;
    case 3: case 8: return 2;
    case 4: case 9: case 11: case 13: return 4;
    case 5: case 10: case 12: case 16: case 17: case 18: return 8;
    default: return 0;
  }
}

std::string describe_start(Reader& r) {
  unsigned char b[8] = {0};
  const std::size_t n = std::size_t(std::min<std::uint64_t>(8, r.size));
  r.bytes(0, n, b);
  if (n >= 8 && std::memcmp(b, "\x89PNG\r\n\x1a\n", 8) == 0) return "a PNG file";
  if (n >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return "a JPEG file";
  if (n >= 4 && std::memcmp(b, "\x89HDF", 4) == 0) return "an HDF5 file";
  if (n == 0) return "empty";
  std::string s;
  for (std::size_t i = 0; i < n; ++i) s += std::isprint(b[i]) ? char(b[i]) : '.';
  return "starts with '" + s + "'";
}

}  // namespace

TiffPages check_tiff(const std::string& path) {
  Reader r(path);
  unsigned char head[4] = {0};
  if (r.size < 8 || !r.bytes(0, 4, head) || !((head[0] == 'I' && head[1] == 'I') || (head[0] == 'M' && head[1] == 'M')))
    throw InputError(path, "format", describe_start(r), "not a TIFF file (no II/MM byte-order mark); give a TIFF or another --format");
  r.big_endian = head[0] == 'M';
  std::uint64_t magic = 0, first = 0;
  r.uint(2, 2, &magic);
  const bool big = magic == 43;
  if (magic != 42 && magic != 43) throw InputError(path, "format", "version " + num(magic), "not a TIFF file (version is not 42 or 43)");
  if (big ? !r.uint(8, 8, &first) : !r.uint(4, 4, &first))
    throw InputError(path, "header", num(r.size) + " bytes", "truncated TIFF header");
  const std::size_t count_size = big ? 8 : 2, entry_size = big ? 20 : 12, next_size = big ? 8 : 4, inline_size = big ? 8 : 4;
  TiffPages out;
  std::set<std::uint64_t> seen;
  struct Page { std::uint64_t w = 0, h = 0, bps = 1, spp = 1, fmt = 1; } page1;
  for (std::uint64_t off = first; off != 0;) {
    const std::size_t k = out.pages + 1;
    const std::string field = "page " + num(k);
    const auto truncated = [&](const std::string& what) {
      return InputError(path, field, "byte " + num(off),
                        "truncated or corrupt: " + what + " (the file has " + num(r.size) + " bytes; " + num(k - 1) +
                            " complete page(s) before it)");
    };
    if (!seen.insert(off).second) throw InputError(path, field, "byte " + num(off), "corrupt: the page chain loops");
    std::uint64_t n = 0;
    if (!r.uint(off, count_size, &n)) throw truncated("the page's directory lies beyond the end of the file");
    if (n == 0 || n > 4096 || off + count_size + n * entry_size + next_size > r.size)
      throw truncated("the page's directory (" + num(n) + " entries) does not fit in the file");
    std::vector<unsigned char> ifd(std::size_t(n * entry_size + next_size));
    r.bytes(off + count_size, ifd.size(), ifd.data());
    Page p;
    std::vector<std::uint64_t> offsets, counts;
    const auto get = [&](const unsigned char* b, std::size_t nb) {
      std::uint64_t v = 0;
      for (std::size_t i = 0; i < nb; ++i) v |= std::uint64_t(b[r.big_endian ? nb - 1 - i : i]) << (8 * i);
      return v;
    };
    for (std::uint64_t e = 0; e < n; ++e) {
      const unsigned char* b = ifd.data() + e * entry_size;
      const std::uint64_t tag = get(b, 2), type = get(b + 2, 2), cnt = big ? get(b + 4, 8) : get(b + 4, 4);
      const unsigned char* val = b + (big ? 12 : 8);
      const std::size_t ts = tiff_type_size(type);
      if (ts == 0 || cnt == 0) continue;
      const bool wanted = tag == 256 || tag == 257 || tag == 258 || tag == 277 || tag == 339 || tag == 273 ||
                          tag == 279 || tag == 324 || tag == 325;
      if (!wanted) continue;
      if (cnt > (std::uint64_t(1) << 28)) throw truncated("tag " + num(tag) + " claims " + num(cnt) + " values");
      std::vector<std::uint64_t> vals;
      const std::uint64_t nbytes = cnt * ts;
      std::vector<unsigned char> raw(static_cast<std::size_t>(nbytes));
      if (nbytes <= inline_size) {
        std::memcpy(raw.data(), val, std::size_t(nbytes));
      } else {
        const std::uint64_t at = big ? get(val, 8) : get(val, 4);
        if (!r.bytes(at, raw.size(), raw.data())) throw truncated("the values of tag " + num(tag) + " lie beyond the end of the file");
      }
      for (std::uint64_t i = 0; i < cnt; ++i) vals.push_back(get(raw.data() + i * ts, ts));
      switch (tag) {
        case 256: p.w = vals[0]; break;
        case 257: p.h = vals[0]; break;
        case 258: p.bps = vals[0]; break;
        case 277: p.spp = vals[0]; break;
        case 339: p.fmt = vals[0]; break;
        case 273: case 324: offsets = vals; break;
        case 279: case 325: counts = vals; break;
      }
    }
    if (p.w == 0 || p.h == 0) throw InputError(path, field, num(p.w) + "x" + num(p.h), "a page without a width or height");
    if (offsets.empty()) throw truncated("the page has no strip or tile offsets");
    for (std::size_t i = 0; i < offsets.size() && i < counts.size(); ++i)
      if (offsets[i] > r.size || counts[i] > r.size - offsets[i])
        throw InputError(path, field, "strip " + num(i) + " at byte " + num(offsets[i]) + " (" + num(counts[i]) + " bytes)",
                         "truncated: the page's data ends beyond the end of the file (" + num(r.size) + " bytes; " +
                             num(k - 1) + " complete page(s) before it)");
    const auto text = [](const Page& q) {
      return num(q.w) + "x" + num(q.h) + ", " + num(q.spp) + " x " + num(q.bps) + " bit" +
             (q.fmt == 3 ? " float" : q.fmt == 2 ? " signed" : "");
    };
    if (k == 1) page1 = p;
    else if (p.w != page1.w || p.h != page1.h || p.bps != page1.bps || p.spp != page1.spp || p.fmt != page1.fmt)
      throw InputError(path, field, text(p), "differs from page 1 (" + text(page1) + "): every page of a volume must have the same size and type");
    out.pages = k;
    off = get(ifd.data() + n * entry_size, next_size);
    if (out.pages > 1000000) throw InputError(path, "pages", num(out.pages), "more than 10^6 pages: corrupt?");
  }
  if (out.pages == 0) throw InputError(path, "pages", "0", "a TIFF without pages");
  out.width = std::size_t(page1.w);
  out.height = std::size_t(page1.h);
  return out;
}

namespace {
struct MetaHeader {
  bool found = false;          // ElementDataFile seen
  std::string data_file;       // as written
  std::uint64_t data_offset = 0;  // LOCAL: where the data starts
  long long header_size = 0;   // external file: bytes to skip (-1: data at the end)
  bool compressed = false;
  std::uint64_t compressed_size = 0;
};

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}
std::string lower(std::string s) {
  for (auto& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

MetaHeader parse_meta(const std::string& path) {
  MetaHeader h;
  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::uint64_t pos = 0;
  for (int lines = 0; lines < 1000 && std::getline(in, line); ++lines) {
    pos += line.size() + 1;
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = lower(trim(line.substr(0, eq))), val = trim(line.substr(eq + 1));
    if (key == "compresseddata") h.compressed = lower(val) == "true";
    else if (key == "compresseddatasize") h.compressed_size = std::strtoull(val.c_str(), nullptr, 10);
    else if (key == "headersize") h.header_size = std::strtoll(val.c_str(), nullptr, 10);
    else if (key == "elementdatafile") {
      h.found = true;
      h.data_file = val;
      h.data_offset = pos;
      break;
    }
  }
  return h;
}

// Bytes that inflate from `len` bytes of `path` at `off` (zlib or gzip); *complete: the stream ended.
std::uint64_t inflated_size(const std::string& path, std::uint64_t off, std::uint64_t len, bool* complete, bool* corrupt,
                            std::vector<unsigned char>* head = nullptr, std::size_t head_bytes = 0) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(off));
  z_stream s{};
  if (inflateInit2(&s, 15 + 32) != Z_OK) throw RuntimeFailure("zlib: inflateInit failed");
  std::vector<unsigned char> ib(1 << 20), ob(1 << 20);
  std::uint64_t out = 0, left = len;
  int rc = Z_OK;
  *complete = *corrupt = false;
  while (rc != Z_STREAM_END && left > 0) {
    in.read(reinterpret_cast<char*>(ib.data()), std::streamsize(std::min<std::uint64_t>(ib.size(), left)));
    const auto got = static_cast<std::size_t>(in.gcount());
    if (got == 0) break;
    left -= got;
    s.next_in = ib.data();
    s.avail_in = unsigned(got);
    do {
      s.next_out = ob.data();
      s.avail_out = unsigned(ob.size());
      rc = inflate(&s, Z_NO_FLUSH);
      if (rc == Z_DATA_ERROR || rc == Z_NEED_DICT || rc == Z_MEM_ERROR) { *corrupt = true; inflateEnd(&s); return out; }
      const std::size_t produced = ob.size() - s.avail_out;
      if (head && head->size() < head_bytes)
        head->insert(head->end(), ob.begin(), ob.begin() + std::ptrdiff_t(std::min(produced, head_bytes - head->size())));
      out += produced;
    } while (s.avail_out == 0 && rc != Z_STREAM_END);
  }
  *complete = rc == Z_STREAM_END;
  inflateEnd(&s);
  return out;
}
}  // namespace

std::string metaimage_data_file(const std::string& path) {
  const MetaHeader h = parse_meta(path);
  if (!h.found || lower(h.data_file) == "local" || h.data_file.find('%') != std::string::npos ||
      h.data_file.rfind("LIST", 0) == 0)
    return "";
  const fs::path p(h.data_file);
  return p.is_absolute() ? p.string() : (fs::path(path).parent_path() / p).string();
}

std::string check_metaimage(const std::string& path, std::uint64_t needed, const std::string& dims_text) {
  const MetaHeader h = parse_meta(path);
  if (!h.found) return "";  // ITK says what is wrong with the header
  const bool local = lower(h.data_file) == "local";
  const std::string data = local ? path : metaimage_data_file(path);
  if (data.empty()) return "";
  if (!local && !fs::exists(data))
    throw InputError(path, "ElementDataFile", h.data_file, "the data file " + data + " does not exist");
  const std::uint64_t size = file_size_of(data);
  std::uint64_t off = local ? h.data_offset : (h.header_size > 0 ? std::uint64_t(h.header_size) : 0);
  if (!local && h.header_size < 0) off = size >= needed ? size - needed : 0;
  const std::uint64_t available = size > off ? size - off : 0;
  const std::string need = "DimSize " + dims_text + " needs " + num(needed) + " bytes of data";
  if (!h.compressed) {
    if (available < needed)
      throw InputError(data, "ElementDataFile", h.data_file + " (" + num(available) + " bytes of data)",
                       "truncated: the header's " + need + "; the file holds " + num(available));
    return local ? "" : data;
  }
  if (h.compressed_size > 0 && h.compressed_size > available)
    throw InputError(data, "CompressedDataSize", num(h.compressed_size),
                     "truncated: the header gives " + num(h.compressed_size) + " compressed bytes; the file holds " + num(available));
  bool complete = false, corrupt = false;
  const std::uint64_t n = inflated_size(data, off, h.compressed_size > 0 ? h.compressed_size : available, &complete, &corrupt);
  if (corrupt || !complete || n < needed)
    throw InputError(data, "CompressedData", num(n) + " bytes inflated",
                     std::string(corrupt ? "corrupt" : "truncated") + ": the compressed data " +
                         (corrupt ? "fails to inflate after " + num(n) + " bytes" : complete ? "ends early" : "is cut short") +
                         "; the header's " + need);
  return local ? "" : data;
}

void check_nifti(const std::string& path, std::uint64_t needed, const std::string& dims_text) {
  const std::string l = lower(path);
  const bool gz = l.size() > 3 && l.compare(l.size() - 3, 3, ".gz") == 0;
  std::vector<unsigned char> head;
  std::uint64_t total = 0;
  bool complete = true, corrupt = false;
  if (gz) {
    total = inflated_size(path, 0, file_size_of(path), &complete, &corrupt, &head, 544);
  } else {
    total = file_size_of(path);
    std::ifstream in(path, std::ios::binary);
    head.resize(std::size_t(std::min<std::uint64_t>(544, total)));
    in.read(reinterpret_cast<char*>(head.data()), std::streamsize(head.size()));
  }
  if (head.size() < 348) return;  // ITK says what is wrong with the header
  const auto le = [&](std::size_t at, std::size_t n, bool swap) {
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < n; ++i) v |= std::uint64_t(head[at + (swap ? n - 1 - i : i)]) << (8 * i);
    return v;
  };
  bool swap = false;
  std::uint64_t sizeof_hdr = le(0, 4, false);
  if (sizeof_hdr != 348 && sizeof_hdr != 540) { swap = true; sizeof_hdr = le(0, 4, true); }
  double vox_offset = 0;
  if (sizeof_hdr == 348) {
    const auto bits = std::uint32_t(le(108, 4, swap));
    float f;
    std::memcpy(&f, &bits, 4);
    vox_offset = f;
  } else if (sizeof_hdr == 540 && head.size() >= 176) {
    vox_offset = double(le(168, 8, swap));
  } else {
    return;
  }
  if (!(vox_offset >= 0)) vox_offset = 0;
  const std::uint64_t off = std::uint64_t(vox_offset);
  const std::uint64_t have = total > off ? total - off : 0;
  if (corrupt || !complete || have < needed)
    throw InputError(path, "data", num(have) + " bytes" + (gz ? " inflated" : ""),
                     std::string(corrupt ? "corrupt" : "truncated") + ": the header's dims " + dims_text + " need " +
                         num(needed) + " bytes of data after vox_offset " + num(off) +
                         (gz && !complete ? "; the compressed stream is cut short" : ""));
}

}  // namespace tomodem::image::checks
