// PNG files of RgbImage buffers (render/images.h) through VTK's vtkPNGWriter / vtkPNGReader.
// VTK is used only inside viz/png.cpp: no rendering window, only the image I/O module.
//
// Orientation: an RgbImage's row 0 is the top of the picture (the first PNG scanline); VTK
// images start at the bottom row, so rows are flipped on the way in and out.
#pragma once

#include <filesystem>

#include "render/images.h"

namespace ptc::viz {

/// Writes an 8-bit RGB PNG atomically: encoded in memory, written to a temporary name in the
/// target's directory and renamed over `path` (toolkit/io/atomic_file.h), so a reader never sees
/// a half-written image and a failed write leaves an existing file untouched.
/// `compression`: zlib level 0..9 (0 = stored, for tests that read the raw scanlines).
/// Throws std::invalid_argument for an empty or inconsistent image (size 0, wrong buffer size)
/// and InputError naming the path when the file cannot be written.
void write_png(const std::filesystem::path& path, const RgbImage& img, int compression = 6);

/// Encodes an image as PNG bytes (same rules as write_png, nothing written).
[[nodiscard]] std::string encode_png(const RgbImage& img, int compression = 6);

/// Reads an 8-bit PNG (grey, grey + alpha, RGB or RGBA; alpha dropped, grey replicated) with
/// vtkPNGReader. Throws InputError naming the path when it is missing or not a readable PNG. The
/// chunk structure (signature, IHDR first, lengths inside the file, CRC-32 of every chunk, IEND)
/// is checked before VTK sees the file: libpng inside vtkPNGReader crashes on truncated data.
[[nodiscard]] RgbImage read_png(const std::filesystem::path& path);

}  // namespace ptc::viz
