// PNG output: round trip through VTK's reader, and the written scanlines checked by an
// independent decoder (stored zlib blocks at compression level 0, PNG filters undone here), so
// that the orientation (row 0 = top) does not rest on VTK agreeing with itself.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "toolkit/core/error.h"
#include "viz/png.h"

namespace fs = std::filesystem;
using ptc::RgbImage;

namespace {

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("ptc_png_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

RgbImage random_image(int w, int h, unsigned seed) {
  RgbImage img(w, h);
  std::mt19937 rng(seed);
  for (auto& b : img.rgb) b = static_cast<std::uint8_t>(rng() & 255);
  return img;
}

std::uint32_t be32(const std::string& s, std::size_t i) {
  return (std::uint32_t(std::uint8_t(s[i])) << 24) | (std::uint32_t(std::uint8_t(s[i + 1])) << 16) |
         (std::uint32_t(std::uint8_t(s[i + 2])) << 8) | std::uint32_t(std::uint8_t(s[i + 3]));
}

// Decodes an 8-bit RGB PNG whose zlib stream uses stored blocks only (compression level 0).
RgbImage decode_stored_png(const std::string& png) {
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  std::size_t i = 8;
  int w = 0, h = 0;
  std::string z;
  while (i + 8 <= png.size()) {
    const std::uint32_t len = be32(png, i);
    const std::string type = png.substr(i + 4, 4);
    if (type == "IHDR") {
      w = int(be32(png, i + 8)), h = int(be32(png, i + 12));
      EXPECT_EQ(png[i + 16], 8);  // bit depth
      EXPECT_EQ(png[i + 17], 2);  // colour type RGB
      EXPECT_EQ(png[i + 20], 0);  // no interlace
    } else if (type == "IDAT") {
      z += png.substr(i + 8, len);
    }
    i += 12 + len;
  }
  // zlib: 2 header bytes, then stored blocks (header byte, LEN, NLEN, bytes).
  std::string raw;
  std::size_t p = 2;
  for (bool last = false; !last;) {
    const auto hdr = std::uint8_t(z.at(p));
    last = hdr & 1;
    EXPECT_EQ((hdr >> 1) & 3, 0) << "not a stored block";
    if (((hdr >> 1) & 3) != 0) return {};
    const std::size_t len = std::uint8_t(z.at(p + 1)) | (std::size_t(std::uint8_t(z.at(p + 2))) << 8);
    raw += z.substr(p + 5, len);
    p += 5 + len;
  }
  RgbImage img(w, h);
  const std::size_t stride = 3 * std::size_t(w);
  EXPECT_EQ(raw.size(), std::size_t(h) * (stride + 1));
  std::vector<std::uint8_t> prev(stride, 0), cur(stride);
  for (int y = 0; y < h; ++y) {
    const int filter = std::uint8_t(raw[std::size_t(y) * (stride + 1)]);
    for (std::size_t x = 0; x < stride; ++x) {
      const int v = std::uint8_t(raw[std::size_t(y) * (stride + 1) + 1 + x]);
      const int a = x >= 3 ? cur[x - 3] : 0, b = prev[x], c = x >= 3 ? prev[x - 3] : 0;
      int pred = 0;
      if (filter == 1) pred = a;
      if (filter == 2) pred = b;
      if (filter == 3) pred = (a + b) / 2;
      if (filter == 4) {
        const int pp = a + b - c, pa = std::abs(pp - a), pb = std::abs(pp - b), pc = std::abs(pp - c);
        pred = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      cur[x] = std::uint8_t((v + pred) & 255);
    }
    std::copy(cur.begin(), cur.end(), img.rgb.begin() + std::ptrdiff_t(std::size_t(y) * stride));
    prev = cur;
  }
  return img;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST(Png, RoundTripThroughVtkReaderIsExact) {
  const fs::path d = temp_dir("rt");
  for (auto [w, h] : {std::pair{1, 1}, std::pair{7, 3}, std::pair{3, 7}, std::pair{64, 33}}) {
    const RgbImage img = random_image(w, h, unsigned(w * 100 + h));
    const fs::path f = d / ("img_" + std::to_string(w) + "x" + std::to_string(h) + ".png");
    ptc::viz::write_png(f, img);
    const RgbImage back = ptc::viz::read_png(f);
    ASSERT_EQ(back.width, w);
    ASSERT_EQ(back.height, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) ASSERT_EQ(back.at(x, y), img.at(x, y)) << "pixel " << x << "," << y;
  }
  fs::remove_all(d);
}

TEST(Png, FirstScanlineIsTopRowIndependentDecoder) {
  // A 5x4 image whose every pixel encodes its own (x, y): a flip or a transposition shows.
  RgbImage img(5, 4);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 5; ++x) img.set(x, y, {std::uint8_t(10 * x), std::uint8_t(50 * y), std::uint8_t(x + 7 * y)});
  const RgbImage dec = decode_stored_png(ptc::viz::encode_png(img, 0));
  ASSERT_EQ(dec.width, 5);
  ASSERT_EQ(dec.height, 4);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 5; ++x) EXPECT_EQ(dec.at(x, y), img.at(x, y)) << "pixel " << x << "," << y;
  // Larger random image (several stored blocks and filter choices).
  const RgbImage big = random_image(300, 130, 5);
  const RgbImage dec2 = decode_stored_png(ptc::viz::encode_png(big, 0));
  EXPECT_EQ(dec2.rgb, big.rgb);
}

TEST(Png, WriteIsAtomicAndReplaces) {
  const fs::path d = temp_dir("atomic");
  const fs::path f = d / "a.png";
  ptc::viz::write_png(f, random_image(4, 4, 1));
  ptc::viz::write_png(f, random_image(2, 3, 2));  // replaces
  EXPECT_EQ(ptc::viz::read_png(f).rgb, random_image(2, 3, 2).rgb);
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(d)) ++files;
  EXPECT_EQ(files, 1u) << "a temporary file was left behind";
  // A missing directory: InputError naming the path, nothing created.
  EXPECT_THROW(ptc::viz::write_png(d / "missing" / "b.png", random_image(2, 2, 3)), ptc::InputError);
  EXPECT_FALSE(fs::exists(d / "missing"));
  fs::remove_all(d);
}

TEST(Png, BadImagesAndFilesAreRefused) {
  EXPECT_THROW((void)ptc::viz::encode_png(RgbImage(0, 5)), std::invalid_argument);
  RgbImage bad(3, 3);
  bad.rgb.pop_back();
  EXPECT_THROW((void)ptc::viz::encode_png(bad), std::invalid_argument);
  EXPECT_THROW((void)ptc::viz::encode_png(RgbImage(2, 2), 10), std::invalid_argument);
  const fs::path d = temp_dir("bad");
  EXPECT_THROW((void)ptc::viz::read_png(d / "none.png"), ptc::InputError);
  std::ofstream(d / "text.png") << "not a png at all";
  EXPECT_THROW((void)ptc::viz::read_png(d / "text.png"), ptc::InputError);
  // A truncated PNG must not be read as a valid image.
  ptc::viz::write_png(d / "t.png", random_image(40, 40, 9));
  const std::string bytes = slurp(d / "t.png");
  std::ofstream(d / "trunc.png", std::ios::binary) << bytes.substr(0, 60);
  EXPECT_THROW((void)ptc::viz::read_png(d / "trunc.png"), ptc::InputError);
  // A flipped byte inside the image data (CRC mismatch), and a file cut just before IEND.
  std::string flipped = bytes;
  flipped[bytes.size() / 2] = char(flipped[bytes.size() / 2] ^ 0x5a);
  std::ofstream(d / "flip.png", std::ios::binary) << flipped;
  EXPECT_THROW((void)ptc::viz::read_png(d / "flip.png"), ptc::InputError);
  std::ofstream(d / "noend.png", std::ios::binary) << bytes.substr(0, bytes.size() - 12);
  EXPECT_THROW((void)ptc::viz::read_png(d / "noend.png"), ptc::InputError);
  fs::remove_all(d);
}
