// What the reader tests share: a mesh read from memory under a file name, and the InputError a
// bad one throws, which must name that file.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <string_view>

#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

namespace ptc::io_test {

/// The file name the bytes stand for in messages: "t.off", "t.obj", ...
inline std::string name_of(MeshFormat f) { return "t." + std::string(to_string(f)); }

inline LoadedMesh read(std::string_view bytes, MeshFormat f) { return read_mesh_from_memory(bytes, f, name_of(f)); }

/// The error of reading `bytes`; a test failure when there is none or it does not name the file.
inline InputError read_error(std::string_view bytes, MeshFormat f) {
  try {
    (void)read(bytes, f);
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), name_of(f));
    EXPECT_NE(std::string(e.what()).find(name_of(f)), std::string::npos) << e.what();
    return e;
  }
  ADD_FAILURE() << "no InputError for:\n" << bytes.substr(0, 200);
  return InputError("", "", "", "");
}

}  // namespace ptc::io_test
