// SceneLoader: loads a scene on a thread of its own so that the frame loop never waits for a file, and a load that blocks (a hung mount) can be abandoned.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "scene_state.h"

namespace flashgs::viewer {

class SceneLoader {
 public:
  using LoadFunction = std::function<LoadedScene(const std::string& path)>;
  explicit SceneLoader(LoadFunction load = [](const std::string& path) { return load_scene(path); });
  // Abandons a running load: destruction never waits for the file.
  ~SceneLoader();
  SceneLoader(const SceneLoader&) = delete;
  SceneLoader& operator=(const SceneLoader&) = delete;

  // Starts loading `path`; false (nothing started) while another load is running.
  bool start(const std::string& path);
  bool busy() const { return m_job != nullptr; }
  // The file being loaded; empty when idle.
  const std::string& path() const { return m_path; }
  // When the load has finished: true, with `scene` set, or `error` set when it failed.
  bool take(LoadedScene* scene, std::string* error);
  // Stops waiting for the running load: its thread ends on its own (its result is dropped)
  // and a new load can start.
  void abandon();
  // Loads of this process still running, abandoned ones included (exit must not wait for them).
  static int running();

 private:
  struct Job;
  LoadFunction m_load;
  std::shared_ptr<Job> m_job;
  std::string m_path;
};

}  // namespace flashgs::viewer
