#include "viz/renderer.h"

#include <vtkActor.h>
#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkCommand.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkInteractorStyleTrackballCamera.h>
#include <vtkMapper.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cmath>

#include "toolkit/core/cancel.h"
#include <stdexcept>
#include <string>

// Mesa's llvmpipe driver keeps small allocations per GL context in a library it unloads again,
// so LeakSanitizer reports them from an unknown module (nothing a suppression can name). The GL
// calls run with leak checking off in sanitizer builds; ASan still checks every access.
#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#define PTC_GL_CALLS __lsan::ScopedDisabler ptc_gl_calls_lsan_off
#else
#define PTC_GL_CALLS
#endif

namespace ptc::viz {
namespace {

constexpr int kMaxSide = 8192;

void check_size(int w, int h) {
  if (w < 1 || h < 1 || w > kMaxSide || h > kMaxSide)
    throw std::invalid_argument("picture size " + std::to_string(w) + "x" + std::to_string(h) + " outside 1..8192");
}

void set_background(vtkRenderer* r, Rgb8 c) { r->SetBackground(c[0] / 255.0, c[1] / 255.0, c[2] / 255.0); }

// The surface and line actors of a mesh picture.
struct MeshActors {
  vtkSmartPointer<vtkActor> surface, lines;
};

MeshActors make_actors(const Mesh& mesh, const MeshStyle& style, const Vec3& eye) {
  if (style.triangle_colours.size() != mesh.triangle_count())
    throw std::invalid_argument("one colour per triangle needed: " + std::to_string(style.triangle_colours.size()) +
                                " colours for " + std::to_string(mesh.triangle_count()) + " triangles");
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(mesh.vertex_count()));
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const Vec3& p = mesh.position(v);
    points->SetPoint(static_cast<vtkIdType>(v), p.x(), p.y(), p.z());
  }
  vtkNew<vtkCellArray> polys;
  polys->AllocateExact(static_cast<vtkIdType>(mesh.triangle_count()), static_cast<vtkIdType>(3 * mesh.triangle_count()));
  vtkNew<vtkUnsignedCharArray> colours;
  colours->SetName("colour");
  colours->SetNumberOfComponents(3);
  colours->SetNumberOfTuples(static_cast<vtkIdType>(mesh.triangle_count()));
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const Tri& f = mesh.triangle(t);
    const vtkIdType ids[3] = {static_cast<vtkIdType>(f[0]), static_cast<vtkIdType>(f[1]), static_cast<vtkIdType>(f[2])};
    polys->InsertNextCell(3, ids);
    for (int k = 0; k < 3; ++k) colours->SetTypedComponent(static_cast<vtkIdType>(t), k, style.triangle_colours[t][k]);
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  poly->SetPolys(polys);
  poly->GetCellData()->SetScalars(colours);

  MeshActors a;
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(poly);
  mapper->SetScalarModeToUseCellData();
  mapper->SetColorModeToDirectScalars();
  mapper->ScalarVisibilityOn();
  a.surface = vtkSmartPointer<vtkActor>::New();
  a.surface->SetMapper(mapper);
  vtkProperty* prop = a.surface->GetProperty();
  prop->SetInterpolationToFlat();
  if (style.lighting) {
    prop->SetAmbient(0.2);
    prop->SetDiffuse(0.8);
    prop->SetSpecular(0.0);
  } else {
    prop->LightingOff();
  }
  if (!style.lines.empty()) {
    // Lines lie on the surface's edges; GL's polygon offset does not keep them in front on
    // Debian's VTK + llvmpipe, so their points move 0.2% of the way towards the eye instead.
    vtkNew<vtkPoints> lifted;
    lifted->SetDataTypeToDouble();
    vtkNew<vtkCellArray> segs;
    for (const auto& e : style.lines) {
      if (e[0] >= mesh.vertex_count() || e[1] >= mesh.vertex_count()) throw std::invalid_argument("line vertex out of range");
      vtkIdType ids[2];
      for (int k = 0; k < 2; ++k) {
        const Vec3& p = mesh.position(e[k]);
        const Vec3 q = p + 0.002 * (eye - p);
        ids[k] = lifted->InsertNextPoint(q.x(), q.y(), q.z());
      }
      segs->InsertNextCell(2, ids);
    }
    vtkNew<vtkPolyData> lp;
    lp->SetPoints(lifted);
    lp->SetLines(segs);
    vtkNew<vtkPolyDataMapper> lm;
    lm->SetInputData(lp);
    lm->ScalarVisibilityOff();
    a.lines = vtkSmartPointer<vtkActor>::New();
    a.lines->SetMapper(lm);
    a.lines->GetProperty()->LightingOff();
    a.lines->GetProperty()->SetColor(style.line_colour[0] / 255.0, style.line_colour[1] / 255.0, style.line_colour[2] / 255.0);
    a.lines->GetProperty()->SetLineWidth(style.line_width);
  }
  return a;
}

void set_camera(vtkRenderer* r, const Mesh& mesh, const bvh::PinholeCamera& cam) {
  vtkCamera* c = r->GetActiveCamera();
  // The focal distance only sets where VTK's trackball turns about: the distance to the mesh's
  // centre along the view direction (at least a small positive value).
  const Box3 b = mesh.referenced_bounds();
  double d = 1.0;
  if (!b.empty()) d = std::max((b.center() - cam.eye).dot(cam.forward), 1e-6 * std::max(1.0, b.extent().norm()));
  const Vec3 f = cam.eye + d * cam.forward;
  c->SetPosition(cam.eye.x(), cam.eye.y(), cam.eye.z());
  c->SetFocalPoint(f.x(), f.y(), f.z());
  c->SetViewUp(cam.up.x(), cam.up.y(), cam.up.z());
  c->SetViewAngle(cam.fov_y_deg);  // vertical, as ours (UseHorizontalViewAngle is off)
  r->ResetCameraClippingRange();
}

// The mesh and camera moved and scaled so that the mesh's box is centred at the origin with an
// extent near 1 (a power-of-two scale: the picture is the same one): VTK's clipping range, depth
// buffer and normals lose a mesh of 1e-30 or 1e20 units (an empty picture, or a black one).
struct Normalised {
  Mesh mesh;
  bvh::PinholeCamera cam;
};
Normalised normalised(const Mesh& mesh, const bvh::PinholeCamera& cam) {
  Normalised n{mesh, cam};
  const Box3 b = mesh.referenced_bounds();
  if (b.empty() || !b.lo.allFinite() || !b.hi.allFinite()) return n;
  const Vec3 c = b.center();
  const double e = b.extent().maxCoeff();
  const double s = e > 0 && std::isfinite(e) ? std::ldexp(1.0, -std::ilogb(e)) : 1.0;
  std::vector<Vec3> pos(mesh.positions().begin(), mesh.positions().end());
  for (Vec3& p : pos) p = (p - c) * s;
  n.mesh = mesh.with_positions(std::move(pos));
  n.cam.eye = (cam.eye - c) * s;
  return n;
}

RgbImage read_back(vtkRenderWindow* win, int w, int h) {
  vtkNew<vtkUnsignedCharArray> px;
  win->GetPixelData(0, 0, w - 1, h - 1, /*front=*/0, px, /*right=*/0);
  RgbImage img(w, h);
  const unsigned char* p = px->GetPointer(0);
  for (int y = 0; y < h; ++y)  // VTK's row 0 is the bottom one
    std::copy(p + 3 * static_cast<std::size_t>(h - 1 - y) * w, p + 3 * static_cast<std::size_t>(h - y) * w,
              img.rgb.begin() + 3 * static_cast<std::ptrdiff_t>(y) * w);
  return img;
}

}  // namespace

struct Renderer::Impl {
  vtkSmartPointer<vtkRenderWindow> window;
  vtkSmartPointer<vtkRenderer> renderer;
};

Renderer::Renderer(const Display& display) : impl_(std::make_unique<Impl>()) {
  if (display.name().empty()) throw std::logic_error("viz::Renderer needs a live Display");
  vtkMapper::SetResolveCoincidentTopologyToPolygonOffset();
  impl_->window = vtkSmartPointer<vtkRenderWindow>::New();
  impl_->window->SetOffScreenRendering(1);
  impl_->window->SetMultiSamples(0);
  impl_->window->SetDisplayId(nullptr);
  impl_->renderer = vtkSmartPointer<vtkRenderer>::New();
  impl_->window->AddRenderer(impl_->renderer);
}

Renderer::~Renderer() {
  PTC_GL_CALLS;
  if (impl_ && impl_->window) impl_->window->Finalize();
}

RgbImage Renderer::mesh(const Mesh& in, const MeshStyle& style, const bvh::PinholeCamera& in_cam, int width, int height) {
  check_size(width, height);
  const Normalised n = normalised(in, in_cam);
  const Mesh& mesh = n.mesh;
  const bvh::PinholeCamera& cam = n.cam;
  MeshActors a = make_actors(mesh, style, cam.eye);
  vtkRenderer* r = impl_->renderer;
  r->RemoveAllViewProps();
  r->AddActor(a.surface);
  if (a.lines) r->AddActor(a.lines);
  set_background(r, style.background);
  impl_->window->SetSize(width, height);
  set_camera(r, mesh, cam);
  PTC_GL_CALLS;
  impl_->window->Render();
  RgbImage img = read_back(impl_->window, width, height);
  r->RemoveAllViewProps();
  return img;
}

RgbImage Renderer::text(int width, int height, std::span<const TextItem> items, Rgb8 background) {
  check_size(width, height);
  vtkRenderer* r = impl_->renderer;
  r->RemoveAllViewProps();
  set_background(r, background);
  for (const TextItem& t : items) {
    vtkNew<vtkTextActor> a;
    a->SetInput(t.text.c_str());
    vtkTextProperty* p = a->GetTextProperty();
    p->SetFontFamilyToArial();
    p->SetFontSize(t.size);
    p->SetBold(t.bold);
    p->SetColor(t.colour[0] / 255.0, t.colour[1] / 255.0, t.colour[2] / 255.0);
    if (t.align < 0) p->SetJustificationToLeft();
    else if (t.align > 0) p->SetJustificationToRight();
    else p->SetJustificationToCentered();
    p->SetVerticalJustificationToCentered();
    a->SetDisplayPosition(t.x, height - 1 - t.y);
    r->AddActor2D(a);
  }
  impl_->window->SetSize(width, height);
  PTC_GL_CALLS;
  impl_->window->Render();
  RgbImage img = read_back(impl_->window, width, height);
  r->RemoveAllViewProps();
  return img;
}

void Renderer::interact(const Mesh& in, const MeshStyle& style, const bvh::PinholeCamera& in_cam, int width, int height,
                        const std::string& title) {
  check_size(width, height);
  const Normalised n = normalised(in, in_cam);
  const Mesh& mesh = n.mesh;
  const bvh::PinholeCamera& cam = n.cam;
  MeshActors a = make_actors(mesh, style, cam.eye);
  vtkNew<vtkRenderer> r;
  r->AddActor(a.surface);
  if (a.lines) r->AddActor(a.lines);
  set_background(r, style.background);
  vtkNew<vtkRenderWindow> win;
  win->AddRenderer(r);
  win->SetSize(width, height);
  win->SetWindowName(title.c_str());
  set_camera(r, mesh, cam);
  PTC_GL_CALLS;
  vtkNew<vtkRenderWindowInteractor> iren;
  vtkNew<vtkInteractorStyleTrackballCamera> st;
  iren->SetInteractorStyle(st);
  iren->SetRenderWindow(win);
  win->Render();
  // Ctrl-C / SIGTERM end the window's event loop (the command then stops as interrupted).
  iren->Initialize();
  vtkNew<vtkCallbackCommand> poll;
  poll->SetCallback([](vtkObject* caller, unsigned long, void*, void*) {
    if (cancel_requested()) static_cast<vtkRenderWindowInteractor*>(caller)->TerminateApp();
  });
  iren->AddObserver(vtkCommand::TimerEvent, poll);
  iren->CreateRepeatingTimer(100);
  iren->Start();
  win->Finalize();
}

}  // namespace ptc::viz
