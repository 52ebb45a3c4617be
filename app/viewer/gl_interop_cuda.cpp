// The CUDA frame path: the backend writes RGBA8 straight into the GL texture through CUDA-GL interop (no host copy).
#include "gl_headers_gl.h"  // before cuda_gl_interop.h, which includes GL/gl.h itself

#include <cuda_gl_interop.h>
#include <cuda_runtime.h>

#include <cstdio>

#include "flashgs/cuda_renderer.h"
#include "flashgs/error.h"
#include "frame_path.h"
#include "image_presenter_gl.h"

namespace flashgs::viewer {
namespace {

std::string cuda_error(const char* what, cudaError_t e) {
  return std::string(what) + ": " + cudaGetErrorName(e) + " (" + cudaGetErrorString(e) + ")";
}

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw Error(cuda_error(what, e));
}

// Two textures in turn: frame N is rendered into one while the window draws and presents
// frame N-1 from the other, so the swap (on Xvfb, a read-back and a copy) does not wait for
// the GPU frame. The texture being rendered stays mapped until the next frame starts; its
// unmap then orders GL's use of it after the render, with no host sync.
class InteropPath final : public FramePath {
 public:
  InteropPath(std::unique_ptr<CudaRenderer> renderer, std::string device)
      : m_renderer(std::move(renderer)), m_device(std::move(device)) {}
  ~InteropPath() override { release_textures(); }

  std::string name() const override { return "CUDA-GL interop (" + m_device + ")"; }
  void set_scene(std::shared_ptr<const Scene> scene) override { m_renderer->set_scene(std::move(scene)); }
  // Only the parts the backend's pool lacks go up (scene_pool.h).
  void set_scene_parts(const std::vector<ScenePart>& parts, std::uint64_t resident_bytes) override {
    m_renderer->set_scene_parts(parts, resident_bytes);
  }
  std::string scene_parts_refusal(const RenderOptions& options) const override {
    return m_renderer->scene_parts_refusal(options);
  }

  int texture_count() const override { return kTextures; }

  void attach_textures(const unsigned* textures, int width, int height) override {
    release_textures();
    // Registered once per texture (registration is the expensive part); only map/unmap run
    // every frame. WriteDiscard: the renderer overwrites every pixel, nothing is read back.
    for (int i = 0; i < kTextures; ++i) {
      check(cudaGraphicsGLRegisterImage(&m_resources[i], textures[i], GL_TEXTURE_2D,
                                        cudaGraphicsRegisterFlagsSurfaceLoadStore),
            "cudaGraphicsGLRegisterImage");
      check(cudaGraphicsResourceSetMapFlags(m_resources[i], cudaGraphicsMapFlagsWriteDiscard),
            "cudaGraphicsResourceSetMapFlags");
    }
    m_width = width;
    m_height = height;
    m_shown = 0;
  }

  void release_textures() override {
    unmap_in_flight();  // errors ignored: the resources go anyway (also runs in the destructor)
    for (cudaGraphicsResource_t& r : m_resources) {
      if (r) cudaGraphicsUnregisterResource(r);
      r = nullptr;
    }
  }

  void render_to_texture(const Camera& camera, const RenderOptions& options, FrameStats* stats) override {
    if (!m_resources[0]) throw Error("CUDA-GL interop: no texture attached");
    present_latest();  // the previous frame: shown from now on
    const int target = 1 - m_shown;
    auto stream = static_cast<cudaStream_t>(m_renderer->stream());
    // Orders this frame's kernels after GL's last use of the texture (it was shown a frame ago).
    check(cudaGraphicsMapResources(1, &m_resources[target], stream), "cudaGraphicsMapResources");
    cudaSurfaceObject_t surface = 0;
    try {
      cudaArray_t array = nullptr;
      check(cudaGraphicsSubResourceGetMappedArray(&array, m_resources[target], 0, 0),
            "cudaGraphicsSubResourceGetMappedArray");
      cudaResourceDesc desc{};
      desc.resType = cudaResourceTypeArray;
      desc.res.array.array = array;
      check(cudaCreateSurfaceObject(&surface, &desc), "cudaCreateSurfaceObject");
      m_renderer->render_to_surface(camera, options, static_cast<std::uint64_t>(surface), stats);
    } catch (...) {
      if (surface) cudaDestroySurfaceObject(surface);
      cudaGraphicsUnmapResources(1, &m_resources[target], stream);
      throw;
    }
    cudaDestroySurfaceObject(surface);
    m_in_flight = target;
  }

  int shown_texture() const override { return m_shown; }

  void present_latest() override {
    const int texture = m_in_flight;
    if (texture < 0) return;
    check(unmap_in_flight(), "cudaGraphicsUnmapResources");
    m_shown = texture;
  }

  void render_image(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats,
                    const std::atomic<bool>*) override {
    m_renderer->render(camera, options, out, stats);
  }

  void tile_counts(const FrameStats& stats, std::vector<std::uint32_t>& out) override {
    if (!stats.tile_pair_counts.empty()) out = stats.tile_pair_counts;
    else m_renderer->download_tile_counts(out);
  }

 private:
  // Unmap orders GL's later use of the texture after the stream's work: no host sync here.
  cudaError_t unmap_in_flight() {
    if (m_in_flight < 0) return cudaSuccess;
    const int texture = m_in_flight;
    m_in_flight = -1;
    return cudaGraphicsUnmapResources(1, &m_resources[texture], static_cast<cudaStream_t>(m_renderer->stream()));
  }

  std::unique_ptr<CudaRenderer> m_renderer;
  std::string m_device;
  static constexpr int kTextures = 2;
  cudaGraphicsResource_t m_resources[kTextures] = {};
  int m_shown = 0;       // the texture the window draws
  int m_in_flight = -1;  // the texture still mapped with a render queued into it, or -1
  int m_width = 0, m_height = 0;
};

}  // namespace

std::unique_ptr<FramePath> make_cuda_path(ImagePresenter* presenter, std::string* why) {
  std::string reason;
  if (!cuda_available(&reason)) {
    *why = "no usable CUDA device (" + reason + ")";
    return nullptr;
  }
  int device = 0;
  cudaGetDevice(&device);
  cudaDeviceProp prop{};
  cudaGetDeviceProperties(&prop, device);
  const std::string device_name = prop.name;
  auto renderer = make_cuda_renderer();
  // Interop needs the GL context to live on a CUDA device; Mesa (llvmpipe) or a display driven
  // by another GPU fails here rather than at the first frame.
  unsigned count = 0;
  int gl_devices[4] = {-1, -1, -1, -1};
  const cudaError_t e = cudaGLGetDevices(&count, gl_devices, 4, cudaGLDeviceListAll);
  bool on_our_device = false;
  for (unsigned i = 0; i < count && i < 4; ++i) on_our_device |= gl_devices[i] == device;
  if (e != cudaSuccess || !on_our_device) {
    cudaGetLastError();  // clear the (non-sticky) error so that later calls do not report it
    *why = e != cudaSuccess ? "CUDA-GL interop refused (" + cuda_error("cudaGLGetDevices", e) + ")"
                            : "CUDA-GL interop refused: the GL context is not on CUDA device " + std::to_string(device);
    // The same host path as the CPU backend's: the renderer fills the tile counts whenever
    // the heat map asks for them (RenderOptions::collect_tile_counts).
    return make_upload_path(std::move(renderer), presenter, "CUDA (" + device_name + ") + host copy, no interop");
  }
  return std::make_unique<InteropPath>(std::move(renderer), device_name);
}

}  // namespace flashgs::viewer
