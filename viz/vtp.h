// ParaView files: one VTK XML PolyData file (.vtp, vtkXMLPolyDataWriter, binary, zlib) per frame
// with the frame's positions, its triangles, cell data (one value per triangle: cluster_id,
// colour_index and every per-cluster metric of the frame, repeated over the cluster's
// triangles) and point data (displacement from the reference frame, 3 components); and the
// .pvd collection that lists the frames with their times (VTK has no .pvd writer: the small
// XML is written here). read_vtp() reads a file back through vtkXMLPolyDataReader (tests, and
// a user's check that ParaView will see what was written).
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "toolkit/mesh/mesh.h"

namespace ptc::viz {

struct VtpArrays {
  std::vector<std::pair<std::string, std::vector<double>>> cell;      ///< one value per triangle each
  std::vector<std::pair<std::string, std::vector<std::int32_t>>> cell_int;  ///< cluster_id, colour_index
  std::vector<std::pair<std::string, std::vector<Vec3>>> point;        ///< one vector per vertex each
};

/// Writes `mesh` at its positions with the arrays to `path` (std::invalid_argument for an array of
/// the wrong length; InputError naming the path when VTK cannot write it).
void write_vtp(const std::filesystem::path& path, const Mesh& mesh, const VtpArrays& arrays);

/// What a .vtp holds, read back by VTK's own reader.
struct VtpContents {
  std::vector<Vec3> points;
  std::vector<std::array<std::int64_t, 3>> triangles;  ///< cells of three points (others: InputError)
  VtpArrays arrays;  ///< every array as double (cell, point: 3 components) and int (cell integer types)
};
[[nodiscard]] VtpContents read_vtp(const std::filesystem::path& path);

/// The .pvd collection: one <DataSet timestep="T" file="NAME"/> per (time, file name).
[[nodiscard]] std::string pvd_xml(const std::vector<std::pair<double, std::string>>& frames);

}  // namespace ptc::viz
