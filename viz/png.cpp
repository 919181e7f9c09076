#include "viz/png.h"

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "toolkit/core/error.h"
#include "toolkit/io/atomic_file.h"

namespace ptc::viz {
namespace {

std::uint32_t crc32(const unsigned char* p, std::size_t n, std::uint32_t crc = 0xffffffffu) {
  for (std::size_t i = 0; i < n; ++i) {
    crc ^= p[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return crc;
}

std::uint32_t be32(const unsigned char* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | std::uint32_t(p[3]);
}

// libpng inside vtkPNGReader crashes on a truncated or corrupted file instead of reporting it,
// so the chunk structure is checked first: signature, IHDR first, every chunk inside the file
// with a correct CRC-32, IEND last. Returns "" or the reason (with the byte offset).
std::string png_structure_error(const std::string& bytes) {
  const auto* b = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::size_t n = bytes.size();
  static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (n < 8 || std::memcmp(b, sig, 8) != 0) return "header: not a PNG file";
  std::size_t i = 8;
  bool first = true;
  while (true) {
    if (i + 12 > n) return byte_loc(i) + ": truncated (no IEND chunk)";
    const std::uint32_t len = be32(b + i);
    if (len > n - i - 12) return byte_loc(i) + ": chunk runs past the end of the file (truncated)";
    const std::string type(bytes.data() + i + 4, 4);
    if (first && type != "IHDR") return byte_loc(i) + ": the first chunk is not IHDR";
    first = false;
    if ((crc32(b + i + 4, 4 + std::size_t(len)) ^ 0xffffffffu) != be32(b + i + 8 + len))
      return byte_loc(i) + ": CRC mismatch in chunk " + type + " (corrupted)";
    i += 12 + std::size_t(len);
    if (type == "IEND") return "";
  }
}

}  // namespace

std::string encode_png(const RgbImage& img, int compression) {
  if (img.width <= 0 || img.height <= 0) throw std::invalid_argument("encode_png: empty image");
  if (img.rgb.size() != 3 * img.pixel_count()) throw std::invalid_argument("encode_png: buffer size does not match");
  if (compression < 0 || compression > 9) throw std::invalid_argument("encode_png: compression must be 0..9");
  vtkNew<vtkImageData> data;
  data->SetDimensions(img.width, img.height, 1);
  data->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* dst = static_cast<std::uint8_t*>(data->GetScalarPointer());
  const std::size_t row = 3 * static_cast<std::size_t>(img.width);
  for (int y = 0; y < img.height; ++y)  // VTK's row 0 is the bottom one
    std::memcpy(dst + static_cast<std::size_t>(img.height - 1 - y) * row, img.rgb.data() + static_cast<std::size_t>(y) * row, row);
  vtkNew<vtkPNGWriter> w;
  w->SetInputData(data);
  w->SetCompressionLevel(compression);
  w->WriteToMemoryOn();
  w->Write();
  vtkUnsignedCharArray* out = w->GetResult();
  if (w->GetErrorCode() != 0 || out == nullptr || out->GetNumberOfValues() == 0)
    throw std::runtime_error("vtkPNGWriter failed to encode the image");
  return std::string(reinterpret_cast<const char*>(out->GetPointer(0)), static_cast<std::size_t>(out->GetNumberOfValues()));
}

void write_png(const std::filesystem::path& path, const RgbImage& img, int compression) {
  const std::string bytes = encode_png(img, compression);
  AtomicFile f(path);
  f.write(bytes);
  f.commit();
}

RgbImage read_png(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path.string(), "", "", "no such file");
  {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in && !in.eof()) throw InputError(path.string(), "", "", "cannot be read");
    if (const std::string why = png_structure_error(bytes); !why.empty()) throw InputError(path.string(), "", "", why);
  }
  vtkNew<vtkPNGReader> r;
  if (!r->CanReadFile(path.c_str())) throw InputError(path.string(), "", "header", "not a PNG file");
  r->SetFileName(path.c_str());
  r->Update();
  vtkImageData* data = r->GetOutput();
  int dims[3] = {0, 0, 0};
  data->GetDimensions(dims);
  vtkDataArray* scalars = data->GetPointData() ? data->GetPointData()->GetScalars() : nullptr;
  if (r->GetErrorCode() != 0 || scalars == nullptr || dims[0] <= 0 || dims[1] <= 0 || dims[2] != 1)
    throw InputError(path.string(), "", "", "cannot decode the PNG image");
  if (scalars->GetDataType() != VTK_UNSIGNED_CHAR)
    throw InputError(path.string(), "", "header", "only 8-bit PNG images are supported");
  const int nc = scalars->GetNumberOfComponents();
  if (nc < 1 || nc > 4) throw InputError(path.string(), "", "header", "unsupported number of channels");
  RgbImage img(dims[0], dims[1]);
  const auto* src = static_cast<const std::uint8_t*>(data->GetScalarPointer());
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const std::uint8_t* p = src + (static_cast<std::size_t>(img.height - 1 - y) * static_cast<std::size_t>(img.width) +
                                     static_cast<std::size_t>(x)) * static_cast<std::size_t>(nc);
      if (nc <= 2)
        img.set(x, y, {p[0], p[0], p[0]});
      else
        img.set(x, y, {p[0], p[1], p[2]});
    }
  return img;
}

}  // namespace ptc::viz
