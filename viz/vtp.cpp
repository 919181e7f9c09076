#include "viz/vtp.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkIdList.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "toolkit/core/error.h"

namespace ptc::viz {

namespace {

// One value per triangle as a named cell array of VTK type A.
template <class A, class V>
void add_cell_array(vtkPolyData* poly, const std::string& name, const std::vector<V>& values, std::size_t triangles) {
  if (values.size() != triangles) throw std::invalid_argument("cell array " + name + ": not one value per triangle");
  vtkNew<A> arr;
  arr->SetName(name.c_str());
  arr->SetNumberOfTuples(static_cast<vtkIdType>(triangles));
  for (std::size_t t = 0; t < triangles; ++t) arr->SetValue(static_cast<vtkIdType>(t), values[t]);
  poly->GetCellData()->AddArray(arr);
}

}  // namespace

void write_vtp(const std::filesystem::path& path, const Mesh& mesh, const VtpArrays& a) {
  const std::size_t T = mesh.triangle_count(), V = mesh.vertex_count();
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(V));
  for (std::size_t v = 0; v < V; ++v) points->SetPoint(static_cast<vtkIdType>(v), mesh.position(v).data());
  vtkNew<vtkCellArray> polys;
  for (std::size_t t = 0; t < T; ++t) {
    const Tri& f = mesh.triangle(t);
    const vtkIdType ids[3] = {static_cast<vtkIdType>(f[0]), static_cast<vtkIdType>(f[1]), static_cast<vtkIdType>(f[2])};
    polys->InsertNextCell(3, ids);
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  poly->SetPolys(polys);
  for (const auto& [name, values] : a.cell_int) add_cell_array<vtkIntArray>(poly, name, values, T);
  for (const auto& [name, values] : a.cell) add_cell_array<vtkDoubleArray>(poly, name, values, T);
  for (const auto& [name, values] : a.point) {
    if (values.size() != V) throw std::invalid_argument("point array " + name + ": not one vector per vertex");
    vtkNew<vtkDoubleArray> arr;
    arr->SetName(name.c_str());
    arr->SetNumberOfComponents(3);
    arr->SetNumberOfTuples(static_cast<vtkIdType>(V));
    for (std::size_t v = 0; v < V; ++v) arr->SetTuple(static_cast<vtkIdType>(v), values[v].data());
    poly->GetPointData()->AddArray(arr);
  }
  if (!a.cell_int.empty()) poly->GetCellData()->SetActiveScalars(a.cell_int.front().first.c_str());
  vtkNew<vtkXMLPolyDataWriter> w;
  w->SetFileName(path.c_str());
  w->SetInputData(poly);
  w->SetDataModeToAppended();
  w->SetCompressorTypeToZLib();
  if (w->Write() != 1) throw InputError(path.string(), "", "", "cannot write the .vtp file");
}

VtpContents read_vtp(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path.string(), "", "", "no such file");
  vtkNew<vtkXMLPolyDataReader> r;
  if (!r->CanReadFile(path.c_str())) throw InputError(path.string(), "", "", "not a VTK XML PolyData file");
  r->SetFileName(path.c_str());
  r->Update();
  vtkPolyData* p = r->GetOutput();
  VtpContents c;
  if (!p || r->GetErrorCode() != 0) throw InputError(path.string(), "", "", "VTK could not read it");
  for (vtkIdType i = 0; i < p->GetNumberOfPoints(); ++i) {
    double q[3];
    p->GetPoint(i, q);
    c.points.emplace_back(q[0], q[1], q[2]);
  }
  vtkCellArray* polys = p->GetPolys();
  vtkNew<vtkIdList> ids;
  polys->InitTraversal();
  std::size_t cell = 0;
  while (polys->GetNextCell(ids)) {
    if (ids->GetNumberOfIds() != 3) throw InputError(path.string(), "", fmt::format("cell {}", cell), "not a triangle");
    c.triangles.push_back({ids->GetId(0), ids->GetId(1), ids->GetId(2)});
    ++cell;
  }
  vtkCellData* cd = p->GetCellData();
  for (int i = 0; i < cd->GetNumberOfArrays(); ++i) {
    vtkDataArray* arr = cd->GetArray(i);
    if (!arr) continue;
    const std::string name = arr->GetName() ? arr->GetName() : "";
    if (arr->GetDataType() == VTK_INT) {
      std::vector<std::int32_t> v(static_cast<std::size_t>(arr->GetNumberOfTuples()));
      for (std::size_t k = 0; k < v.size(); ++k) v[k] = static_cast<std::int32_t>(arr->GetComponent(static_cast<vtkIdType>(k), 0));
      c.arrays.cell_int.emplace_back(name, std::move(v));
    } else {
      std::vector<double> v(static_cast<std::size_t>(arr->GetNumberOfTuples()));
      for (std::size_t k = 0; k < v.size(); ++k) v[k] = arr->GetComponent(static_cast<vtkIdType>(k), 0);
      c.arrays.cell.emplace_back(name, std::move(v));
    }
  }
  vtkPointData* pd = p->GetPointData();
  for (int i = 0; i < pd->GetNumberOfArrays(); ++i) {
    vtkDataArray* arr = pd->GetArray(i);
    if (!arr || arr->GetNumberOfComponents() != 3) continue;
    std::vector<Vec3> v(static_cast<std::size_t>(arr->GetNumberOfTuples()));
    for (std::size_t k = 0; k < v.size(); ++k) {
      double q[3];
      arr->GetTuple(static_cast<vtkIdType>(k), q);
      v[k] = Vec3(q[0], q[1], q[2]);
    }
    c.arrays.point.emplace_back(arr->GetName() ? arr->GetName() : "", std::move(v));
  }
  return c;
}

std::string pvd_xml(const std::vector<std::pair<double, std::string>>& frames) {
  std::string s = "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
  for (const auto& [t, file] : frames) {
    std::string esc;
    for (char ch : file) {
      switch (ch) {
        case '&': esc += "&amp;"; break;
        case '<': esc += "&lt;"; break;
        case '>': esc += "&gt;"; break;
        case '"': esc += "&quot;"; break;
        default: esc += ch;
      }
    }
    s += fmt::format("    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>\n", t, esc);
  }
  s += "  </Collection>\n</VTKFile>\n";
  return s;
}

}  // namespace ptc::viz
