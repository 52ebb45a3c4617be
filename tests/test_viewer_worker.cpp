// The viewer's background rendering without a window: the render worker (newest request wins, cancel, restart), the comparison's task, the rendered-FPS meter, the frame-path notes and the one baseline rule.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <condition_variable>
#include <atomic>
#include <functional>
#include <future>
#include <mutex>
#include <thread>
#include <stdexcept>
#include <vector>

#include "background_job.h"
#include "camera_controller.h"
#include "compare_task.h"
#include "flashgs/generators.h"
#include "path_note.h"
#include "rate_meter.h"
#include "read_rate_history.h"
#include "render_gate.h"
#include "render_worker.h"
#include "viewer_settings.h"

namespace fv = flashgs::viewer;

namespace {

// A renderer whose frames block until released (or cancelled through the flag, when it
// honours it), recording the width of each frame it starts; width 13 throws.
class GatedRenderer final : public flashgs::Renderer {
 public:
  explicit GatedRenderer(bool honours_cancel) : m_honours_cancel(honours_cancel) {}
  std::string name() const override { return "gated"; }
  void set_scene(std::shared_ptr<const flashgs::Scene>) override {}
  void render(const flashgs::Camera& camera, const flashgs::RenderOptions&, flashgs::Image& out,
              flashgs::FrameStats* stats) override {
    std::unique_lock<std::mutex> lock(m_mutex);
    m_started.push_back(camera.width);
    m_changed.notify_all();
    if (camera.width == 13) throw std::runtime_error("width 13 refused");
    while (m_releases == 0) {
      if (m_honours_cancel && cancel_requested()) {
        stats->cancelled = true;
        return;
      }
      m_changed.wait_for(lock, std::chrono::milliseconds(1));
    }
    --m_releases;
    out.resize(camera.width, 1);
  }
  void release(int frames = 1) {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_releases += frames;
    m_changed.notify_all();
  }
  // Waits (up to 30 s) until `count` frames have started; returns their widths.
  std::vector<int> wait_started(std::size_t count) {
    std::unique_lock<std::mutex> lock(m_mutex);
    m_changed.wait_for(lock, std::chrono::seconds(30), [&] { return m_started.size() >= count; });
    return m_started;
  }

 private:
  bool m_honours_cancel;
  std::mutex m_mutex;
  std::condition_variable m_changed;
  std::vector<int> m_started;
  int m_releases = 0;
};

// A frame path whose host-memory renders go through a RenderWorker, as the CPU path's do
// (without its GL upload); `background`: it says it renders in the background.
class WorkerPath final : public fv::FramePath {
 public:
  WorkerPath(std::unique_ptr<flashgs::Renderer> renderer, bool background)
      : m_worker(std::move(renderer), nullptr), m_background(background) {}
  std::string name() const override { return "worker path"; }
  void set_scene(std::shared_ptr<const flashgs::Scene>) override {}
  void set_scene_parts(const std::vector<flashgs::ScenePart>&, std::uint64_t) override {}
  void attach_textures(const unsigned*, int, int) override {}
  void release_textures() override {}
  void render_to_texture(const flashgs::Camera&, const flashgs::RenderOptions&, flashgs::FrameStats*) override {}
  bool renders_in_background() const override { return m_background; }
  void render_image(const flashgs::Camera& camera, const flashgs::RenderOptions& options, flashgs::Image& out,
                    flashgs::FrameStats* stats, const std::atomic<bool>* cancel) override {
    m_worker.with_renderer([&](flashgs::Renderer& r) { r.render(camera, options, out, stats); }, cancel);
  }
  void tile_counts(const flashgs::FrameStats&, std::vector<std::uint32_t>&) override {}

 private:
  fv::RenderWorker m_worker;
  bool m_background;
};

// Baseline (left) against flash (right) at `width` x 1, one timed round: kJobRenders renders
// (each side's warm-up, then each side once).
constexpr int kJobRenders = 4;
fv::CompareJob job_of_width(int width) {
  fv::CompareJob job;
  job.camera.width = width;
  job.camera.height = 1;
  job.left = flashgs::RenderOptions::baseline();
  job.rounds = 1;
  return job;
}

// A frame path whose renders take no time but report the frame times `ms_of(render index,
// baseline?)` says, recording which side each render drew.
class TimedPath final : public fv::FramePath {
 public:
  explicit TimedPath(std::function<double(int, bool)> ms_of) : m_ms_of(std::move(ms_of)) {}
  std::string name() const override { return "timed path"; }
  void set_scene(std::shared_ptr<const flashgs::Scene>) override {}
  void set_scene_parts(const std::vector<flashgs::ScenePart>&, std::uint64_t) override {}
  void attach_textures(const unsigned*, int, int) override {}
  void release_textures() override {}
  void render_to_texture(const flashgs::Camera&, const flashgs::RenderOptions&, flashgs::FrameStats*) override {}
  void render_image(const flashgs::Camera& camera, const flashgs::RenderOptions& options, flashgs::Image& out,
                    flashgs::FrameStats* stats, const std::atomic<bool>*) override {
    out.resize(camera.width, camera.height);
    stats->times.total_ms = m_ms_of(int(sides.size()), options.is_baseline());
    sides.push_back(options.is_baseline() ? 'B' : 'F');
  }
  void tile_counts(const flashgs::FrameStats&, std::vector<std::uint32_t>&) override {}
  std::string sides;  // "FB..." in render order

 private:
  std::function<double(int, bool)> m_ms_of;
};

fv::FrameRequest request_of_width(int width) {
  fv::FrameRequest r;
  r.camera.width = width;
  r.camera.height = 1;
  return r;
}

}  // namespace

TEST(ViewerRenderWorker, TheNewestRequestWinsAndTheOneInFlightIsCancelled) {
  auto owned = std::make_unique<GatedRenderer>(true);
  GatedRenderer* gated = owned.get();
  int wakes = 0;
  std::mutex wakes_mutex;
  fv::RenderWorker worker(std::move(owned), [&] {
    std::lock_guard<std::mutex> lock(wakes_mutex);
    ++wakes;
  });
  worker.request(request_of_width(1));
  ASSERT_EQ(gated->wait_started(1), std::vector<int>({1}));
  EXPECT_TRUE(worker.busy());
  // Two more while 1 renders: 1 is stopped, 2 is replaced before it starts, 3 renders.
  worker.request(request_of_width(2));
  const std::uint64_t id3 = worker.request(request_of_width(3));
  ASSERT_EQ(gated->wait_started(2), std::vector<int>({1, 3}));
  gated->release();
  worker.wait_until_idle();
  EXPECT_FALSE(worker.busy());
  fv::FinishedFrame frame;
  ASSERT_TRUE(worker.take(&frame));
  EXPECT_EQ(frame.id, id3);
  EXPECT_EQ(frame.image.width, 3);
  EXPECT_TRUE(frame.error.empty());
  EXPECT_FALSE(worker.take(&frame)) << "one frame finished, one delivered";
  std::lock_guard<std::mutex> lock(wakes_mutex);
  EXPECT_EQ(wakes, 1) << "the cancelled frame must not wake the viewer";
}

TEST(ViewerRenderWorker, ABackendThatCannotStopStillShowsItsFrame) {
  auto owned = std::make_unique<GatedRenderer>(false);
  GatedRenderer* gated = owned.get();
  fv::RenderWorker worker(std::move(owned), nullptr);
  worker.request(request_of_width(1));
  gated->wait_started(1);
  worker.request(request_of_width(2), /*cancel_in_flight=*/true);
  gated->release();  // frame 1 completes although asked to stop
  ASSERT_EQ(gated->wait_started(2), std::vector<int>({1, 2}));
  fv::FinishedFrame frame;
  EXPECT_TRUE(worker.take(&frame));
  EXPECT_EQ(frame.image.width, 1) << "a finished frame is shown while the next one renders";
  gated->release();
  worker.wait_until_idle();
  ASSERT_TRUE(worker.take(&frame));
  EXPECT_EQ(frame.image.width, 2);
}

TEST(ViewerRenderWorker, UsingTheRendererMeanwhileRestartsTheFrameInFlight) {
  auto owned = std::make_unique<GatedRenderer>(true);
  GatedRenderer* gated = owned.get();
  fv::RenderWorker worker(std::move(owned), nullptr);
  worker.request(request_of_width(5));
  gated->wait_started(1);
  bool ran = false;
  worker.with_renderer([&](flashgs::Renderer& r) {  // e.g. set_scene: runs once frame 5 stopped
    EXPECT_EQ(r.name(), "gated");
    ran = true;
  });
  EXPECT_TRUE(ran);
  ASSERT_EQ(gated->wait_started(2), std::vector<int>({5, 5})) << "the stopped frame is rendered again";
  gated->release();
  worker.wait_until_idle();
  fv::FinishedFrame frame;
  ASSERT_TRUE(worker.take(&frame));
  EXPECT_EQ(frame.image.width, 5);
}

TEST(ViewerRenderWorker, AFailingFrameIsDeliveredWithItsError) {
  fv::RenderWorker worker(std::make_unique<GatedRenderer>(true), nullptr);
  worker.request(request_of_width(13));
  worker.wait_until_idle();
  fv::FinishedFrame frame;
  ASSERT_TRUE(worker.take(&frame));
  EXPECT_EQ(frame.error, "width 13 refused");
}

TEST(ViewerRenderWorker, DestroyingItStopsTheFrameInFlight) {
  auto owned = std::make_unique<GatedRenderer>(true);
  GatedRenderer* gated = owned.get();
  auto worker = std::make_unique<fv::RenderWorker>(std::move(owned), nullptr);
  worker->request(request_of_width(7));
  gated->wait_started(1);
  worker.reset();  // returns: the frame saw the cancel flag (else this test hangs)
  SUCCEED();
}

TEST(ViewerRateMeter, CountsEventsPerSecondAndFallsToZero) {
  fv::RateMeter meter;
  EXPECT_EQ(meter.rate(0.0), 0.0);
  for (int i = 0; i <= 10; ++i) meter.record(10.0 + 0.1 * i);  // 10 per second
  EXPECT_NEAR(meter.rate(11.0), 10.0, 0.01);
  EXPECT_EQ(meter.rate(12.5), 0.0) << "no frames in the last second: idle, not the old rate";
}

// The streamed bytes per second: one sample per half second, a new stream (its count back at
// zero) starts over without a negative rate, and only the last half minute is kept.
TEST(ViewerReadRate, SamplesBytesPerSecondEveryHalfSecond) {
  fv::ReadRateHistory h;
  h.observe(5.0, 1000);
  EXPECT_TRUE(h.rates().empty()) << "the first look only starts the count";
  h.observe(5.2, 2000);
  EXPECT_TRUE(h.rates().empty()) << "less than half a second";
  h.observe(5.5, 6000);
  ASSERT_EQ(h.rates().size(), 1u);
  EXPECT_FLOAT_EQ(h.rates()[0], 10000.0f);  // 5000 bytes in 0.5 s
  h.observe(6.5, 6000);
  EXPECT_FLOAT_EQ(h.latest(), 0.0f);
  h.observe(7.0, 10);  // a new stream
  EXPECT_EQ(h.rates().size(), 2u);
  h.observe(8.0, 1010);
  EXPECT_FLOAT_EQ(h.latest(), 1000.0f);
  for (int i = 0; i < 100; ++i) h.observe(9.0 + i, 1010);
  EXPECT_EQ(static_cast<int>(h.rates().size()), fv::ReadRateHistory::kLength);
}

TEST(ViewerPathNote, TheDriverTextBecomesPlainWords) {
  EXPECT_EQ(fv::plain_path_note("no usable CUDA device (cudaGetDeviceCount: CUDA driver version is insufficient for "
                                "CUDA runtime version)"),
            "no NVIDIA GPU found: rendering on the CPU");
  EXPECT_EQ(fv::plain_path_note("this build has no CUDA backend"), "built without CUDA: rendering on the CPU");
  EXPECT_EQ(fv::plain_path_note(""), "");
  EXPECT_EQ(fv::plain_path_note("something new"), "something new");
}

// B then the Flash radio (before: B replaced every switch by the baseline's "off", so flash
// came back with every optimisation off).
TEST(ViewerSettings, SwitchingToTheBaselineAndBackKeepsTheSwitches) {
  flashgs::RenderOptions o;
  o.tight_bbox = false;  // a user's choice
  const flashgs::RenderOptions before = o;
  fv::switch_algorithm(o, flashgs::Algorithm::baseline);
  EXPECT_TRUE(o.is_baseline());
  EXPECT_FALSE(o.uses_opacity_radius()) << "the baseline uses none of the optimisations";
  fv::switch_algorithm(o, flashgs::Algorithm::flash);
  EXPECT_TRUE(o == before);
}

TEST(ViewerNavigation, ExactOnlyAtTheSceneCamerasAspect) {
  const float target[3] = {0, 0, 0}, up[3] = {0, 1, 0};
  const auto cameras = flashgs::make_orbit_cameras(target, up, 3.0f, 1.0f, 4, 1920, 1080, 60.0f);
  fv::CameraController c;
  c.reset(glm::vec3(0.0f), 1.0f, glm::vec3(0, 1, 0));
  c.snap_to(cameras[1]);
  const float fov = cameras[1].horizontal_fov_degrees();
  EXPECT_TRUE(c.exact_scene_camera(640, 360, fov));
  EXPECT_FALSE(c.exact_scene_camera(1280, 800, fov)) << "16:10 is the pose, not the camera";
  EXPECT_FALSE(c.exact_scene_camera(640, 360, fov + 5.0f));
}

// A new scene does not wait for the frame in flight, even on a backend that cannot stop it
// (before, set_scene waited for the renderer: the window froze for a whole CPU frame).
TEST(ViewerRenderWorker, ANewSceneDoesNotWaitForTheFrameInFlight) {
  class SceneRecorder final : public flashgs::Renderer {
   public:
    std::string name() const override { return "scenes"; }
    void set_scene(std::shared_ptr<const flashgs::Scene> scene) override { m_scene = scene; }
    void render(const flashgs::Camera& camera, const flashgs::RenderOptions&, flashgs::Image& out,
                flashgs::FrameStats*) override {
      while (!released) std::this_thread::sleep_for(std::chrono::milliseconds(1));  // ignores the cancel flag
      out.resize(camera.width, m_scene ? int(m_scene->size()) : 0);
    }
    std::shared_ptr<const flashgs::Scene> m_scene;
    std::atomic<bool> released{false};
  };
  auto owned = std::make_unique<SceneRecorder>();
  SceneRecorder* recorder = owned.get();
  fv::RenderWorker worker(std::move(owned), nullptr);
  worker.request(request_of_width(4));
  auto scene = std::make_shared<flashgs::Scene>();
  scene->opacities.resize(3);  // size() counts opacities
  auto call = std::async(std::launch::async, [&] { worker.set_scene(scene); });
  const bool returned = call.wait_for(std::chrono::seconds(5)) == std::future_status::ready;
  recorder->released = true;
  call.wait();
  EXPECT_TRUE(returned) << "set_scene waited for the frame in flight";
  worker.request(request_of_width(6));
  worker.wait_until_idle();
  fv::FinishedFrame frame;
  ASSERT_TRUE(worker.take(&frame));
  EXPECT_EQ(frame.image.width, 6);
  EXPECT_EQ(frame.image.height, 3) << "rendered with the new scene";
}

// A streamed cut's parts reach the worker's renderer as parts (set_scene_parts, with the GPU
// cap), before the next frame, and a later scene replaces parts not yet set.
TEST(ViewerRenderWorker, PartsReachTheRendererAsPartsBeforeTheNextFrame) {
  class PartsRecorder final : public flashgs::Renderer {
   public:
    std::string name() const override { return "parts"; }
    void set_scene(std::shared_ptr<const flashgs::Scene> scene) override { drawn = scene ? scene->size() : 0; }
    void set_scene_parts(const std::vector<flashgs::ScenePart>& parts, std::uint64_t resident) override {
      part_sets++;
      last_count = parts.size();
      resident_bytes = resident;
      drawn = flashgs::scene_parts_size(parts);
    }
    void render(const flashgs::Camera& camera, const flashgs::RenderOptions&, flashgs::Image& out,
                flashgs::FrameStats*) override {
      out.resize(camera.width, int(drawn));
    }
    std::atomic<int> part_sets{0};
    std::size_t last_count = 0, drawn = 0;
    std::uint64_t resident_bytes = 0;
  };
  auto owned = std::make_unique<PartsRecorder>();
  PartsRecorder* recorder = owned.get();
  fv::RenderWorker worker(std::move(owned), nullptr);
  auto source = std::make_shared<flashgs::Scene>();
  source->opacities.resize(10);
  worker.set_scene_parts({{1, source, 0, 4}, {2, source, 6, 3}}, 12345);
  worker.request(request_of_width(5));
  worker.wait_until_idle();
  fv::FinishedFrame frame;
  ASSERT_TRUE(worker.take(&frame));
  EXPECT_EQ(recorder->part_sets, 1);
  EXPECT_EQ(recorder->last_count, 2u);
  EXPECT_EQ(recorder->resident_bytes, 12345u);
  EXPECT_EQ(frame.image.height, 7) << "not rendered with the parts";
  // Parts, then a scene before the worker ran: the scene wins, the parts are never set.
  worker.with_renderer([&](flashgs::Renderer&) {
    worker.set_scene_parts({{3, source, 0, 1}}, 0);
    worker.set_scene(source);
  });
  worker.request(request_of_width(5));
  worker.wait_until_idle();
  ASSERT_TRUE(worker.take(&frame));
  EXPECT_EQ(recorder->part_sets, 1);
  EXPECT_EQ(frame.image.height, 10);
}

// The caller's flag stops a render made through with_renderer (the comparison's renders on
// its task thread); without one, the worker's own cancels never reach it.
TEST(ViewerRenderWorker, ARenderThroughWithRendererStopsOnTheCallersFlag) {
  auto owned = std::make_unique<GatedRenderer>(true);
  GatedRenderer* gated = owned.get();
  fv::RenderWorker worker(std::move(owned), nullptr);
  std::atomic<bool> cancel{false};
  flashgs::FrameStats stats;
  auto call = std::async(std::launch::async, [&] {
    worker.with_renderer(
        [&](flashgs::Renderer& r) {
          flashgs::Image image;
          r.render(request_of_width(3).camera, {}, image, &stats);
        },
        &cancel);
  });
  gated->wait_started(1);
  cancel = true;
  ASSERT_EQ(call.wait_for(std::chrono::seconds(30)), std::future_status::ready) << "the flag did not stop the render";
  EXPECT_TRUE(stats.cancelled);
  worker.request(request_of_width(4));  // the worker's own frames still render (its flag is back)
  gated->release();
  worker.wait_until_idle();
  fv::FinishedFrame frame;
  ASSERT_TRUE(worker.take(&frame));
  EXPECT_EQ(frame.image.width, 4);
}

// On a path that renders in the background, start() returns while the renders run (before,
// the comparison ran in the frame loop and the window froze until it ended); the outcome,
// with its texture bytes, is taken once, and a second comparison meanwhile is refused.
TEST(ViewerCompareTask, ItRunsBesideTheCallerAndItsOutcomeIsTakenOnce) {
  auto owned = std::make_unique<GatedRenderer>(true);
  GatedRenderer* gated = owned.get();
  WorkerPath path(std::move(owned), true);
  std::atomic<int> wakes{0};
  fv::CompareTask task([&] { ++wakes; });
  auto start = std::async(std::launch::async, [&] { return task.start(path, job_of_width(6)); });
  gated->wait_started(1);
  const bool returned = start.wait_for(std::chrono::seconds(30)) == std::future_status::ready;
  if (!returned) gated->release(kJobRenders);  // a start() that waits for the renders: let it end
  ASSERT_TRUE(returned) << "start() waited for the comparison's renders";
  ASSERT_TRUE(start.get());
  fv::CompareOutcome outcome;
  EXPECT_TRUE(task.busy());
  EXPECT_FALSE(task.take(&outcome)) << "nothing to take while it renders";
  EXPECT_FALSE(task.start(path, job_of_width(6))) << "one comparison at a time";
  gated->release(kJobRenders);
  task.wait();
  EXPECT_EQ(wakes.load(), 1);
  ASSERT_TRUE(task.take(&outcome));
  EXPECT_TRUE(outcome.result.valid) << outcome.result.error;
  EXPECT_EQ(outcome.result.right_label, "flash");
  EXPECT_EQ(outcome.result.left_label, "baseline");
  EXPECT_EQ(outcome.left_rgba.size(), 6u * 4u);
  EXPECT_EQ(outcome.right_rgba.size(), 6u * 4u);
  EXPECT_EQ(outcome.difference_rgba.size(), 6u * 4u);
  EXPECT_FALSE(outcome.cancelled());
  EXPECT_FALSE(task.take(&outcome)) << "taken once";
  EXPECT_FALSE(task.busy());
  EXPECT_EQ(task.elapsed_seconds(), 0.0);
}

// cancel() stops the render in flight (the worker's renderer sees the task's flag) and the
// outcome says so; the next comparison starts afresh.
TEST(ViewerCompareTask, CancelStopsTheRenderInFlight) {
  auto owned = std::make_unique<GatedRenderer>(true);
  GatedRenderer* gated = owned.get();
  WorkerPath path(std::move(owned), true);
  fv::CompareTask task;
  ASSERT_TRUE(task.start(path, job_of_width(5)));
  gated->wait_started(1);
  task.cancel();
  task.wait();  // returns: the render saw the flag (else this test hangs)
  fv::CompareOutcome outcome;
  ASSERT_TRUE(task.take(&outcome));
  EXPECT_TRUE(outcome.cancelled());
  EXPECT_FALSE(outcome.result.valid);
  EXPECT_TRUE(outcome.left_rgba.empty());
  EXPECT_EQ(gated->wait_started(1).size(), 1u) << "the second side never started";
  ASSERT_TRUE(task.start(path, job_of_width(5)));
  gated->release(kJobRenders);
  task.wait();
  ASSERT_TRUE(task.take(&outcome));
  EXPECT_TRUE(outcome.result.valid) << outcome.result.error;
}

// A comparison finished but not yet taken when the scene changes is dropped all the same.
TEST(ViewerCompareTask, ACancelAfterTheRendersEndedStillDropsTheOutcome) {
  auto owned = std::make_unique<GatedRenderer>(true);
  owned->release(kJobRenders);
  WorkerPath path(std::move(owned), true);
  fv::CompareTask task;
  ASSERT_TRUE(task.start(path, job_of_width(4)));
  task.wait();
  task.cancel();
  fv::CompareOutcome outcome;
  ASSERT_TRUE(task.take(&outcome));
  EXPECT_TRUE(outcome.cancelled());
  EXPECT_TRUE(outcome.difference_rgba.empty());
}

TEST(ViewerCompareTask, DestroyingItStopsTheComparisonInFlight) {
  auto owned = std::make_unique<GatedRenderer>(true);
  GatedRenderer* gated = owned.get();
  WorkerPath path(std::move(owned), true);
  {
    fv::CompareTask task;
    ASSERT_TRUE(task.start(path, job_of_width(7)));
    gated->wait_started(1);
  }  // returns: the task cancelled its render and joined (else this test hangs)
  SUCCEED();
}

// On a path that renders in the caller's thread (a GPU path) the comparison is done when
// start() returns: one code path, no thread; a failing render is the outcome's error.
TEST(ViewerCompareTask, OnAPathThatRendersHereItIsDoneWhenStartReturns) {
  auto owned = std::make_unique<GatedRenderer>(true);
  owned->release(kJobRenders);
  WorkerPath path(std::move(owned), false);
  fv::CompareTask task;
  ASSERT_TRUE(task.start(path, job_of_width(3)));
  fv::CompareOutcome outcome;
  ASSERT_TRUE(task.take(&outcome));
  EXPECT_TRUE(outcome.result.valid) << outcome.result.error;
  ASSERT_TRUE(task.start(path, job_of_width(13)));
  ASSERT_TRUE(task.take(&outcome));
  EXPECT_FALSE(outcome.result.valid);
  EXPECT_EQ(outcome.result.error, "width 13 refused");
}

// The speed-up is a measurement: each side warmed up untimed, then rounds that render both
// sides in alternating order; the figures are medians with their range, and rounds that
// disagree on the faster side are called noise. (Before, one cold render per side was timed.)
TEST(ViewerCompareTiming, WarmedInterleavedRoundsGiveAMedianWithItsSpread) {
  // Warm-ups (renders 0 and 1) are slow, as a first render at a size is; then the baseline
  // takes 200 ms and flash 100 ms, except one flash render that the machine slowed to 150 ms.
  TimedPath path([](int render, bool baseline) {
    if (render < 2) return 1000.0;
    if (render == 6) return 150.0;  // round 2's flash render
    return baseline ? 200.0 : 100.0;
  });
  flashgs::Camera camera;
  camera.width = 4;
  camera.height = 2;
  std::vector<int> progress;
  const fv::CompareResult r = fv::run_compare(path, camera, flashgs::RenderOptions::baseline(), flashgs::RenderOptions{},
                                              5, nullptr, [&](int done, int total) {
                                                EXPECT_EQ(total, 12);
                                                progress.push_back(done);
                                              });
  ASSERT_TRUE(r.valid) << r.error;
  EXPECT_EQ(path.sides, "FB" "FB" "BF" "FB" "BF" "FB") << "warm-up, then alternating order";
  EXPECT_EQ(progress.size(), 12u);
  EXPECT_EQ(progress.back(), 12);
  EXPECT_EQ(r.right_ms.samples, 5);
  EXPECT_DOUBLE_EQ(r.right_ms.median, 100.0) << "the warm-ups are not timed";
  EXPECT_DOUBLE_EQ(r.right_ms.max, 150.0);
  EXPECT_DOUBLE_EQ(r.left_ms.median, 200.0);
  EXPECT_DOUBLE_EQ(r.speed_up.median, 2.0);
  EXPECT_NEAR(r.speed_up.min, 200.0 / 150.0, 1e-9);
  EXPECT_DOUBLE_EQ(r.speed_up.max, 2.0);
  EXPECT_FALSE(fv::within_noise(r.speed_up));
  EXPECT_EQ(fv::speed_up_text(r), "speed-up 2.00x (1.33-2.00 over 5 rounds)");

  // Two configurations as fast as each other: the rounds disagree, and the panel says so.
  TimedPath even([](int render, bool baseline) { return 100.0 + ((render / 2) % 2 == (baseline ? 0 : 1) ? 5.0 : 0.0); });
  const fv::CompareResult e = fv::run_compare(even, camera, flashgs::RenderOptions::baseline(), flashgs::RenderOptions{}, 4);
  ASSERT_TRUE(e.valid) << e.error;
  EXPECT_TRUE(fv::within_noise(e.speed_up)) << fv::speed_up_text(e);
  EXPECT_NE(fv::speed_up_text(e).find(": within noise"), std::string::npos) << fv::speed_up_text(e);
}

// A path export's frame job: beside the caller, one at a time, its outcome taken once; the
// cancel flag reaches it; a throw becomes its message.
TEST(ViewerBackgroundJob, OneJobBesideTheCallerItsOutcomeTakenOnce) {
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<int> done_calls{0};
  flashgs::viewer::BackgroundJob job([&] { ++done_calls; });
  ASSERT_TRUE(job.start(true, [released](const std::atomic<bool>&) -> std::string {
    released.wait();  // the caller has gone on: start() did not wait for this
    return "";
  }));
  EXPECT_TRUE(job.busy());
  EXPECT_FALSE(job.start(true, [](const std::atomic<bool>&) -> std::string { return ""; })) << "a second job while busy";
  std::string error = "unset";
  EXPECT_FALSE(job.take(&error)) << "taken before it ended";
  release.set_value();
  job.wait();
  ASSERT_TRUE(job.take(&error));
  EXPECT_EQ(error, "");
  EXPECT_FALSE(job.take(&error)) << "taken twice";
  EXPECT_FALSE(job.busy());
  EXPECT_EQ(done_calls.load(), 1);
  // At once when not on a thread, and a throw is the job's message.
  ASSERT_TRUE(job.start(false, [](const std::atomic<bool>&) -> std::string { throw std::runtime_error("disk full"); }));
  ASSERT_TRUE(job.take(&error));
  EXPECT_EQ(error, "disk full");
}

TEST(ViewerBackgroundJob, CancelRaisesTheJobsFlag) {
  flashgs::viewer::BackgroundJob job;
  std::atomic<bool> started{false};
  ASSERT_TRUE(job.start(true, [&started](const std::atomic<bool>& cancel) -> std::string {
    started = true;
    while (!cancel) std::this_thread::yield();  // a render checking its flag between tiles
    return "cancelled";
  }));
  while (!started) std::this_thread::yield();
  job.cancel();
  job.wait();
  std::string error;
  ASSERT_TRUE(job.take(&error));
  EXPECT_EQ(error, "cancelled");
}

// What the --render-gate renderer passes on: each render reaches the inner renderer only once
// the gate file exists, or at once when its cancel flag is raised (which the inner renderer
// then sees, and stops the frame as cancelled).
namespace {

class RecordingRenderer final : public flashgs::Renderer {
 public:
  explicit RecordingRenderer(std::string gate_file) : m_gate_file(std::move(gate_file)) {}
  std::string name() const override { return "recording"; }
  void set_scene(std::shared_ptr<const flashgs::Scene>) override {}
  void render(const flashgs::Camera& camera, const flashgs::RenderOptions&, flashgs::Image& out,
              flashgs::FrameStats* stats) override {
    ++renders;
    gate_was_open = std::filesystem::exists(m_gate_file);
    if (cancel_requested()) {
      stats->cancelled = true;
      return;
    }
    out.resize(camera.width, 1);
  }
  std::atomic<int> renders{0};
  std::atomic<bool> gate_was_open{false};

 private:
  std::string m_gate_file;
};

std::string fresh_gate_file(const char* name) {
  const auto dir = std::filesystem::temp_directory_path() / "flashgs_render_gate";
  std::filesystem::create_directories(dir);
  const std::string file = (dir / name).string();
  std::filesystem::remove(file);
  return file;
}

void open_gate(const std::string& file) {
  if (FILE* f = std::fopen(file.c_str(), "w")) std::fclose(f);
}

// Waits (up to 30 s) until a render waits at `gated`'s closed gate.
bool wait_until_held(const fv::FileGatedRenderer& gated) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!gated.waiting() && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  return gated.waiting();
}

}  // namespace

TEST(ViewerRenderGate, AnOpenGateRendersAtOnce) {
  const std::string gate = fresh_gate_file("open");
  open_gate(gate);
  auto owned = std::make_unique<RecordingRenderer>(gate);
  RecordingRenderer* inner = owned.get();
  fv::FileGatedRenderer gated(std::move(owned), gate);
  EXPECT_EQ(gated.name(), "recording");
  flashgs::Image image;
  flashgs::FrameStats stats;
  gated.render(request_of_width(7).camera, {}, image, &stats);
  EXPECT_EQ(inner->renders, 1);
  EXPECT_EQ(image.width, 7);
  EXPECT_FALSE(stats.cancelled);
}

TEST(ViewerRenderGate, AClosedGateHoldsTheRenderUntilTheFileAppears) {
  const std::string gate = fresh_gate_file("closed");
  auto owned = std::make_unique<RecordingRenderer>(gate);
  RecordingRenderer* inner = owned.get();
  fv::FileGatedRenderer gated(std::move(owned), gate);
  flashgs::Image image;
  flashgs::FrameStats stats;
  std::thread render([&] { gated.render(request_of_width(5).camera, {}, image, &stats); });
  const bool held = wait_until_held(gated);
  EXPECT_TRUE(held) << "the render never waited at the closed gate";
  EXPECT_EQ(inner->renders, 0) << "it rendered before the gate opened";
  open_gate(gate);
  render.join();
  EXPECT_FALSE(gated.waiting());
  EXPECT_EQ(inner->renders, 1);
  EXPECT_TRUE(inner->gate_was_open) << "the inner render ran with the gate closed";
  EXPECT_EQ(image.width, 5);
}

TEST(ViewerRenderGate, ACancelledRenderLeavesTheClosedGateAsACancelledFrame) {
  const std::string gate = fresh_gate_file("cancelled");
  auto owned = std::make_unique<RecordingRenderer>(gate);
  RecordingRenderer* inner = owned.get();
  fv::FileGatedRenderer gated(std::move(owned), gate);
  std::atomic<bool> cancel{false};
  gated.set_cancel_flag(&cancel);
  flashgs::Image image;
  flashgs::FrameStats stats;
  std::thread render([&] { gated.render(request_of_width(5).camera, {}, image, &stats); });
  EXPECT_TRUE(wait_until_held(gated)) << "the render never waited at the closed gate";
  cancel = true;
  render.join();  // returns with the gate still closed
  EXPECT_EQ(inner->renders, 1);
  EXPECT_FALSE(inner->gate_was_open);
  EXPECT_TRUE(stats.cancelled) << "the inner renderer did not get the cancel flag";
}
