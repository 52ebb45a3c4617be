// SceneLoader: loads a scene on a thread of its own so that the frame loop never waits for a file, and a load that blocks (a hung mount) can be abandoned.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "flashgs/load_progress.h"
#include "scene_state.h"

namespace flashgs::viewer {

// How far a load is, 0..1, over both of its steps: reading the file's bytes and decoding its
// Gaussians, half the bar each where the reader reports both (the bytes of a large scene are
// read long before its Gaussians are decoded); the one reported alone fills the bar. -1 while
// nothing is reported.
float load_fraction(std::uint64_t bytes_done, std::uint64_t bytes_total, std::uint64_t gaussians_done,
                    std::uint64_t gaussians_total);

class SceneLoader {
 public:
  // Loads `path`, reporting into `progress` (and stopping when it asks to).
  using LoadFunction = std::function<LoadedScene(const std::string& path, LoadProgress& progress)>;
  explicit SceneLoader(LoadFunction load = [](const std::string& path, LoadProgress& progress) {
    return load_scene(path, "", &progress);
  });
  // Abandons a running load: destruction never waits for the file.
  ~SceneLoader();
  SceneLoader(const SceneLoader&) = delete;
  SceneLoader& operator=(const SceneLoader&) = delete;

  // Starts loading `path` (with `load` instead of the constructor's function when given);
  // false (nothing started) while another load is running.
  bool start(const std::string& path, LoadFunction load = {});
  bool busy() const { return m_job != nullptr; }
  // The file being loaded; empty when idle.
  const std::string& path() const { return m_path; }
  // The running load's progress (null when idle): its fields may all be 0 while the reader
  // does not report them.
  const LoadProgress* progress() const;
  // Seconds since the running load started (0 when idle).
  double elapsed_seconds() const;
  // When the load has finished: true, with `scene` set, or `error` set when it failed.
  bool take(LoadedScene* scene, std::string* error);
  // Stops waiting for the running load and asks it to stop (LoadProgress::cancel_requested):
  // its thread ends on its own (its result is dropped) and a new load can start.
  void abandon();
  // Loads of this process still running, abandoned ones included (exit must not wait for them).
  static int running();
  // Each load started from now on waits, before it reads anything, until `gate_file` exists
  // or it is abandoned (--load-gate: tests act while a load is surely in flight).
  void set_gate(std::string gate_file) { m_gate_file = std::move(gate_file); }
  // The running load waits at the closed gate now.
  bool waiting_at_gate() const;

 private:
  struct Job;
  LoadFunction m_load;
  std::shared_ptr<Job> m_job;
  std::string m_path;
  std::string m_gate_file;
  std::chrono::steady_clock::time_point m_started;
};

}  // namespace flashgs::viewer
