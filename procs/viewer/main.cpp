// omnislam-viewer: shows what the SLAM process is doing (docs/user/viewer.md). Subscribes SLAM_POSE,
// SLAM_MAP, SLAM_PARTICLES, SLAM_ASSOCIATIONS, SLAM_LOCALISATION, GROUND_TRUTH_POSE, GROUND_TRUTH_MAP,
// OMNI_IMAGE and OMNI_FEATURES (each optional) and draws vision::renderSlamView; --map FILE draws a
// saved map until the first SLAM_MAP (the global localiser's hypotheses are drawn over it):
//   live window  (default) an OpenCV window redrawn a few times a second; q or Esc quits;
//   headless     --headless --out-dir DIR [--every N]: no display; writes DIR/frame_<step>.png
//                every N SLAM steps, DIR/localisation_<n>.png every N SLAM_LOCALISATION messages
//                (while the global localiser searches there are no steps), and DIR/final.png at
//                the end (SIGINT/SIGTERM);
//   from a log   --headless --log FILE.lcm --out-dir DIR: reads the log at full speed, same output.
// A SLAM step is one SLAM_POSE and the map, particles and associations published after it; it is
// drawn when the next step starts (or at the end), so that every part of it is in the picture.
#include <CLI/CLI.hpp>

#include <opencv2/highgui.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <algorithm>

#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/node.h"
#include "omnislam/lcmio/signals.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/runtime/map_file.h"
#include "viewer_state.h"

using namespace omnislam;
namespace fs = std::filesystem;

namespace {

struct Settings {
  std::string url, name = "viewer", out_dir, log, map;
  bool headless = false;
  int every = 0;
  double fps = 10.0;
  vision::SlamViewOptions view;
};

/// Writes PNG files of the view into out_dir.
class PngWriter {
 public:
  explicit PngWriter(std::string dir) : dir_(std::move(dir)) {}
  bool enabled() const { return !dir_.empty(); }
  void write(const std::string& file, const cv::Mat& img) {
    const std::string path = dir_ + "/" + file;
    if (!cv::imwrite(path, img, {cv::IMWRITE_PNG_COMPRESSION, 6}))
      throw std::runtime_error("cannot write '" + path + "'");
    ++written_;
  }
  int written() const { return written_; }

 private:
  std::string dir_;
  int written_ = 0;
};

/// The state plus the rule "a step is complete when the next one starts".
class Viewer {
 public:
  Viewer(const Settings& s, std::string title) : s_(s), title_(std::move(title)), png_(s.out_dir) {}
  viewer::ViewerState& state() { return state_; }

  cv::Mat render() {
    vision::SlamViewOptions o = s_.view;
    if (!state_.anyImage()) o.image_width_px = 0;
    return vision::renderSlamView(state_.viewData(title_), o);
  }
  /// Before a new SLAM_POSE is applied: the previous step is complete.
  void beforePose(const pose_t& m) {
    if (!state_.hasPose() || m.utime == state_.lastPoseUtime()) return;
    const int64_t step = state_.steps();
    if (png_.enabled() && s_.every > 0 && step % s_.every == 0) {
      char name[40];
      std::snprintf(name, sizeof name, "frame_%06lld.png", static_cast<long long>(step));
      png_.write(name, render());
    }
  }
  /// After a SLAM_LOCALISATION is applied (a frame of the global localiser: no SLAM step is drawn
  /// while it searches): every N of them, localisation_<count>.png.
  void afterLocalisation() {
    ++localisations_;
    if (png_.enabled() && s_.every > 0 && localisations_ % s_.every == 0) {
      char name[48];
      std::snprintf(name, sizeof name, "localisation_%06lld.png", static_cast<long long>(localisations_));
      png_.write(name, render());
    }
  }
  void writeFinal() {
    if (png_.enabled()) png_.write("final.png", render());
  }
  int written() const { return png_.written(); }

 private:
  const Settings& s_;
  std::string title_;
  PngWriter png_;
  viewer::ViewerState state_;
  int64_t localisations_ = 0;
};

/// The saved map of --map as view landmarks (loadMap refuses a bad file, naming why).
std::vector<vision::ViewLandmark> savedMapLandmarks(const std::string& path) {
  std::vector<vision::ViewLandmark> out;
  for (const slam::Landmark& l : runtime::loadMap(path).landmarks) {
    vision::ViewLandmark v;
    v.id = static_cast<int64_t>(l.id);
    v.p_m = l.p_LinW_m;
    v.cov_xy_m2 = l.cov_LinW_m2.topLeftCorner<2, 2>();
    v.type = l.type == slam::LandmarkType::kTypeI ? 1 : 2;
    v.kind = l.kind == slam::LandmarkKind::kVerticalLine ? 2 : 1;
    out.push_back(v);
  }
  return out;
}

void loadSavedMap(const Settings& s, viewer::ViewerState& st) {
  if (!s.map.empty()) st.setSavedMap(savedMapLandmarks(s.map), fs::path(s.map).filename().string());
}

// ---- live (window or headless) ---------------------------------------------------------------

/// The PNG frames that could not be written: their count and the first one's reason.
struct PngFailures {
  int64_t count = 0;
  std::string first;
};

/// Subscribes the viewer's state to every channel it shows.
void subscribeLive(lcmio::Node& node, Viewer& v, PngFailures& failures) {
  auto& st = v.state();
  lcmio::InputOptions truth_opt;
  truth_opt.queue_capacity = 2000;  // 50 Hz: a slow redraw must not lose truth poses
  node.subscribe<pose_t>(channels::kSlamPose, [&](const pose_t& m) {
    // A frame that cannot be written (full disk, folder gone) is reported, and the pose still
    // applied: otherwise every later pose would retry the same file and be refused with it.
    try {
      v.beforePose(m);
    } catch (const std::exception& e) {
      if (failures.count++ == 0) failures.first = e.what();
      node.error(e.what());
    }
    st.onSlamPose(m);
  });
  node.subscribe<map_t>(channels::kSlamMap, [&](const map_t& m) { st.onSlamMap(m); });
  node.subscribe<particles_t>(channels::kSlamParticles, [&](const particles_t& m) { st.onParticles(m); });
  node.subscribe<associations_t>(channels::kSlamAssociations, [&](const associations_t& m) { st.onAssociations(m); });
  node.subscribe<slam_localisation_t>(channels::kSlamLocalisation, [&](const slam_localisation_t& m) {
    st.onLocalisation(m);
    try {
      v.afterLocalisation();
    } catch (const std::exception& e) {
      if (failures.count++ == 0) failures.first = e.what();
      node.error(e.what());
    }
  });
  node.subscribe<pose_t>(
      channels::kGroundTruthPose, [&](const pose_t& m) { st.onTruthPose(m); }, truth_opt);
  node.subscribe<map_t>(channels::kGroundTruthMap, [&](const map_t& m) { st.onTruthMap(m); });
  node.subscribe<image_t>(channels::kOmniImage, [&](const image_t& m) {
    std::string why;
    if (!st.onImage(m, &why)) node.reject(channels::kOmniImage, "frame seq " + std::to_string(m.seq) + ": " + why);
  });
  node.subscribe<features_t>(channels::kOmniFeatures, [&](const features_t& m) { st.onFeatures(m); });
}

/// Handles the bus and redraws the window (if any) at s.fps until a stop, 'q', Esc or a closed window.
void loopLive(lcmio::Node& node, const Settings& s, Viewer& v, const std::string& win) {
  const bool window = !s.headless;
  const auto period = std::chrono::duration<double>(1.0 / s.fps);
  auto next_draw = std::chrono::steady_clock::now();
  while (!lcmio::stopRequested()) {
    if (!node.handleFor(0.01)) break;
    // Drain what is queued before drawing: one message per loop would fall behind a fast bus
    // (truth at 50 Hz times the simulator's speed-up) and LCM would drop the rest.
    const auto drain_until = std::chrono::steady_clock::now() + std::chrono::milliseconds(50);
    while (!lcmio::stopRequested() && std::chrono::steady_clock::now() < drain_until &&
           node.lcm().handleTimeout(0) > 0) {
    }
    node.setDetail(std::to_string(v.state().steps()) + " SLAM steps, " + std::to_string(v.written()) + " PNG files");
    if (!window) continue;
    const auto now = std::chrono::steady_clock::now();
    if (now >= next_draw) {
      cv::imshow(win, v.render());
      next_draw = now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    }
    const int key = cv::waitKey(1);
    if (key == 'q' || key == 'Q' || key == 27) break;
    if (cv::getWindowProperty(win, cv::WND_PROP_VISIBLE) < 1.0) break;  // closed by the user
  }
}

int runLive(const Settings& s) {
  lcmio::Node node(s.name, app::lcmUrl(s.url));
  Viewer v(s, "omnislam live" + (s.url.empty() ? std::string() : "  " + s.url));
  loadSavedMap(s, v.state());
  PngFailures failures;
  subscribeLive(node, v, failures);
  node.setState(process_status_t::STATE_RUNNING);
  node.publishStatus();

  const bool window = !s.headless;
  const std::string win = "omnislam-viewer";
  if (window) {
    cv::namedWindow(win, cv::WINDOW_NORMAL | cv::WINDOW_KEEPRATIO | cv::WINDOW_GUI_NORMAL);
    cv::resizeWindow(win, s.view.map_width_px + s.view.image_width_px, s.view.height_px);
  }
  std::cerr << node.tag() << (window ? "window" : "headless") << " on " << (s.url.empty() ? "$LCM_DEFAULT_URL" : s.url)
            << (s.out_dir.empty() ? std::string() : ", PNG files into " + s.out_dir) << std::endl;
  loopLive(node, s, v, win);
  node.setState(process_status_t::STATE_STOPPING);
  v.writeFinal();
  node.setState(process_status_t::STATE_FINISHED);
  node.publishStatus();
  if (window) cv::destroyAllWindows();
  const auto& c = node.counters();
  std::cerr << node.tag() << v.state().steps() << " SLAM steps, " << v.written() << " PNG files written; "
            << c.messages_in << " messages in, " << c.decode_errors << " decode errors, " << c.rejected_inputs
            << " rejected" << std::endl;
  if (failures.count > 0) {
    std::cerr << node.tag() << failures.count << " PNG FILES NOT WRITTEN (the first: " << failures.first << ")"
              << std::endl;
    return app::kFailure;
  }
  return app::kOk;
}

// ---- from a log -------------------------------------------------------------------------------

/// Decodes, validates and checks time order like lcmio::Node, for the events of a log.
class LogDispatcher {
 public:
  template <class Msg>
  void on(const std::string& channel, std::function<void(const Msg&)> fn) {
    handlers_[channel] = [this, channel, fn = std::move(fn)](const lcmio::LogEvent& ev) {
      ++in_;
      std::string why_not;
      auto m = lcmio::decodeAs<Msg>(ev, &why_not);
      if (!m) return refuse(decode_errors_, channel + ": cannot decode as " + Msg::getTypeName() + ": " + why_not);
      if (auto why = lcmio::validate(*m)) return refuse(rejected_, channel + ": " + *why);
      if (auto why = time_order_[channel].admit(m->utime)) return refuse(rejected_, channel + ": " + *why);
      fn(*m);
    };
  }
  void dispatch(const lcmio::LogEvent& ev) {
    const auto it = handlers_.find(ev.channel);
    if (it != handlers_.end()) it->second(ev);
  }
  void reject(const std::string& why) { refuse(rejected_, why); }
  int64_t in() const { return in_; }
  int64_t decodeErrors() const { return decode_errors_; }
  int64_t rejected() const { return rejected_; }

 private:
  void refuse(int64_t& counter, const std::string& why) {
    ++counter;
    if (++reports_ <= 20 || reports_ % 100 == 0) std::cerr << "[viewer] rejected " << why << std::endl;
  }
  std::map<std::string, std::function<void(const lcmio::LogEvent&)>> handlers_;
  std::map<std::string, lcmio::UtimeOrder> time_order_;  ///< as lcmio::Node's default InputOptions
  int64_t in_ = 0, decode_errors_ = 0, rejected_ = 0, reports_ = 0;
};

int runLog(const Settings& s) {
  Viewer v(s, "omnislam  " + fs::path(s.log).filename().string());
  auto& st = v.state();
  loadSavedMap(s, st);
  LogDispatcher d;
  d.on<pose_t>(channels::kSlamPose, [&](const pose_t& m) {
    v.beforePose(m);
    st.onSlamPose(m);
  });
  d.on<map_t>(channels::kSlamMap, [&](const map_t& m) { st.onSlamMap(m); });
  d.on<particles_t>(channels::kSlamParticles, [&](const particles_t& m) { st.onParticles(m); });
  d.on<associations_t>(channels::kSlamAssociations, [&](const associations_t& m) { st.onAssociations(m); });
  d.on<slam_localisation_t>(channels::kSlamLocalisation, [&](const slam_localisation_t& m) {
    st.onLocalisation(m);
    v.afterLocalisation();
  });
  d.on<pose_t>(channels::kGroundTruthPose, [&](const pose_t& m) { st.onTruthPose(m); });
  d.on<map_t>(channels::kGroundTruthMap, [&](const map_t& m) { st.onTruthMap(m); });
  d.on<image_t>(channels::kOmniImage, [&](const image_t& m) {
    std::string why;
    if (!st.onImage(m, &why))
      d.reject(std::string(channels::kOmniImage) + ": frame seq " + std::to_string(m.seq) + ": " + why);
  });
  d.on<features_t>(channels::kOmniFeatures, [&](const features_t& m) { st.onFeatures(m); });
  const auto t0 = std::chrono::steady_clock::now();
  auto next_progress = t0 + std::chrono::seconds(2);
  int64_t events = 0;
  lcmio::LogReader reader(s.log);
  lcmio::LogEvent ev;
  while (!lcmio::stopRequested() && reader.next(ev)) {  // SIGINT: stop reading, write the final view
    ++events;
    d.dispatch(ev);
    const auto now = std::chrono::steady_clock::now();
    if (now >= next_progress && reader.result().file_bytes > 0) {  // progress every 2 s
      next_progress = now + std::chrono::seconds(2);
      const double done = reader.result().shareRead();
      const double el = std::chrono::duration<double>(now - t0).count();
      std::fprintf(stderr, "[viewer] %lld SLAM steps, %.0f%% of the log, %.1f steps/s, about %.0f s left\n",
                   static_cast<long long>(st.steps()), 100.0 * done, st.steps() / el,
                   done > 0 ? el * (1.0 - done) / done : 0.0);
    }
  }
  const lcmio::LogReadResult& got = reader.result();
  v.writeFinal();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cerr << "[viewer] " << s.log << ": " << events << " events, " << st.steps() << " SLAM steps, " << v.written()
            << " PNG files written to " << s.out_dir << " in " << wall << " s; " << d.decodeErrors()
            << " decode errors, " << d.rejected() << " rejected" << std::endl;
  if (st.steps() == 0) std::cerr << "[viewer] warning: no SLAM_POSE in the log" << std::endl;
  if (const auto problem = got.problem(s.log); problem && !lcmio::stopRequested())
    std::cerr << "[viewer] warning: " << *problem << std::endl;
  return app::kOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{
      "omnislam-viewer: the SLAM map, particles, trajectories and the image with its features, live or to PNG"};
  Settings s;
  cli.add_option("--url", s.url, "LCM URL (default: $LCM_DEFAULT_URL)");
  cli.add_option("--name", s.name, "process name in PROCESS_STATUS");
  cli.add_flag("--headless", s.headless, "no window: write PNG files into --out-dir");
  cli.add_option("--out-dir", s.out_dir, "folder for frame_<step>.png and final.png (created if missing)");
  cli.add_option("--every", s.every,
                 "write the view every N SLAM steps and every N SLAM_LOCALISATION messages (0: only final.png)")
      ->check(CLI::Range(0, 1000000));
  cli.add_option("--log", s.log, "read this LCM log at full speed instead of the bus (needs --headless)")
      ->check(CLI::ExistingFile);
  cli.add_option("--map", s.map, "a saved map (omnislam-slam --save-map) drawn until the first SLAM_MAP")
      ->check(CLI::ExistingFile);
  cli.add_option("--fps", s.fps, "window redraws per second")->check(omnislam::app::FiniteRange(0.5, 60.0));
  cli.add_option("--map-width", s.view.map_width_px, "map panel width, pixels")->check(CLI::Range(300, 4000));
  cli.add_option("--image-width", s.view.image_width_px, "image panel width, pixels (0: no image panel)")
      ->check(CLI::Range(0, 4000));
  cli.add_option("--height", s.view.height_px, "view height, pixels")->check(CLI::Range(300, 4000));
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);  // a bad flag: exit 2
  return app::runMain("omnislam-viewer", [&]() -> int {
    if (!s.log.empty() && !s.headless)
      throw std::invalid_argument(
          "--log needs --headless (to watch a log in the window, replay it with lcm-logplayer)");
    if (s.headless && s.out_dir.empty()) throw std::invalid_argument("--headless needs --out-dir DIR");
    if (!s.out_dir.empty()) {
      std::error_code ec;
      fs::create_directories(s.out_dir, ec);
      if (!fs::is_directory(s.out_dir)) throw std::invalid_argument("--out-dir '" + s.out_dir + "' cannot be created");
    }
    auto set = [](const char* var) {
      const char* v = std::getenv(var);
      return v && *v;
    };
    if (!s.headless && !set("DISPLAY") && !set("WAYLAND_DISPLAY"))
      throw std::invalid_argument("no display (DISPLAY is not set): use --headless --out-dir DIR, or xvfb-run");
    lcmio::installStopHandlers();
    return s.log.empty() ? runLive(s) : runLog(s);
  });
}
