#pragma once
// A PNG reader for the tests, independent of the writer (libs/image/src/outputs.cpp): checks the
// signature and every chunk's CRC, inflates IDAT with zlib and undoes all five row filters of the
// PNG spec (section 9), for 8-bit RGB without interlace, the only kind the tools write.
#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

namespace tomodem::test {

struct RgbImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // row by row, R G B
  const uint8_t* at(int x, int y) const { return &rgb[3 * (std::size_t(y) * width + x)]; }
};

inline RgbImage read_png_rgb(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string f((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto be32 = [&](std::size_t at) {
    if (at + 4 > f.size()) throw std::runtime_error(path + ": cut short");
    return uint32_t(uint8_t(f[at])) << 24 | uint32_t(uint8_t(f[at + 1])) << 16 | uint32_t(uint8_t(f[at + 2])) << 8 |
           uint32_t(uint8_t(f[at + 3]));
  };
  if (f.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) != 0) throw std::runtime_error(path + ": no PNG signature");
  RgbImage img;
  std::string idat;
  bool ended = false;
  for (std::size_t at = 8; !ended;) {
    const uint32_t len = be32(at);
    const std::string type = f.substr(at + 4, 4);
    if (at + 12 + len > f.size()) throw std::runtime_error(path + ": chunk " + type + " cut short");
    const auto* body = reinterpret_cast<const Bytef*>(f.data() + at + 4);
    if (crc32(0, body, uInt(len + 4)) != be32(at + 8 + len)) throw std::runtime_error(path + ": bad CRC in " + type);
    const std::string data = f.substr(at + 8, len);
    if (type == "IHDR") {
      img.width = int(be32(at + 8));
      img.height = int(be32(at + 12));
      if (data.substr(8) != std::string("\x08\x02\x00\x00\x00", 5)) throw std::runtime_error(path + ": not 8-bit RGB");
    } else if (type == "IDAT") {
      idat += data;
    }
    ended = type == "IEND";
    at += 12 + len;
  }
  const std::size_t stride = 3 * std::size_t(img.width);
  std::vector<uint8_t> raw(std::size_t(img.height) * (1 + stride));
  uLongf raw_size = uLongf(raw.size());
  if (uncompress(raw.data(), &raw_size, reinterpret_cast<const Bytef*>(idat.data()), uLong(idat.size())) != Z_OK ||
      raw_size != raw.size())
    throw std::runtime_error(path + ": IDAT does not inflate to height x (1 + 3 width) bytes");
  img.rgb.assign(std::size_t(img.height) * stride, 0);
  for (int y = 0; y < img.height; ++y) {
    const uint8_t filter = raw[std::size_t(y) * (1 + stride)];
    const uint8_t* src = &raw[std::size_t(y) * (1 + stride) + 1];
    uint8_t* row = &img.rgb[std::size_t(y) * stride];
    const uint8_t* up = y > 0 ? row - stride : nullptr;
    for (std::size_t i = 0; i < stride; ++i) {
      const int a = i >= 3 ? row[i - 3] : 0, b = up ? up[i] : 0, c = up && i >= 3 ? up[i - 3] : 0;
      int pred = 0;
      if (filter == 1) pred = a;
      else if (filter == 2) pred = b;
      else if (filter == 3) pred = (a + b) / 2;
      else if (filter == 4) {  // Paeth
        const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
        pred = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      } else if (filter != 0) throw std::runtime_error(path + ": unknown row filter");
      row[i] = uint8_t(src[i] + pred);
    }
  }
  return img;
}

}  // namespace tomodem::test
