// The back end's schedule and worker (back_end_runner.h).
#include "omnislam/runtime/back_end_runner.h"

#include <algorithm>
#include <chrono>

namespace omnislam::runtime {

namespace {

/// The solve of one graph, on the worker: the correction for the filter and the report.
std::pair<slam::MapCorrection, BackEndReport> solveJob(smoothing::Graph graph, std::vector<slam::Landmark> map,
                                                       smoothing::SolverOptions options) {
  const smoothing::Solution s = smoothing::solve(graph, options);
  BackEndReport r;
  r.ok = s.ok;
  r.failure = s.failure;
  r.solved_at_utime = graph.keyframes.back().utime;
  r.num_keyframes = static_cast<int>(graph.keyframes.size());
  r.num_landmarks = static_cast<int>(graph.landmarks.size());
  r.num_bearings = static_cast<int>(graph.bearings.size());
  r.num_removed = static_cast<int>(s.removed.size());
  r.iterations = s.iterations;
  r.final_cost = s.final_cost;
  if (!s.ok) return {slam::MapCorrection{}, r};
  for (std::size_t k = 0; k < graph.keyframes.size(); ++k) r.keyframe_utimes.push_back(graph.keyframes[k].utime);
  r.keyframe_poses = s.keyframe_poses;
  return {smoothing::correctionFrom(graph, s, map), r};
}

}  // namespace

BackEndRunner::BackEndRunner(const smoothing::BackEndOptions& options, const smoothing::GraphOptions& graph,
                             bool wait_for_solves)
    : options_(options), graph_(graph), wait_(wait_for_solves) {}

BackEndRunner::~BackEndRunner() {
  if (job_ && job_->result.valid()) job_->result.wait();
}

bool BackEndRunner::loopClosure(const smoothing::KeyframeRecord& r) {
  bool closure = false;
  for (const std::int64_t id : r.landmark_of_measurement) {
    if (id < 0) continue;
    const auto key = static_cast<std::uint64_t>(id);
    auto it = std::lower_bound(last_seen_.begin(), last_seen_.end(), key,
                               [](const auto& e, std::uint64_t k) { return e.first < k; });
    if (it != last_seen_.end() && it->first == key) {
      closure = closure || keyframes_ - it->second >= options_.loop_closure_keyframes;
      it->second = keyframes_;
    } else {
      last_seen_.insert(it, {key, keyframes_});
    }
  }
  return closure;
}

bool BackEndRunner::solveDue(bool loop_closure) const {
  if (job_) return false;  // one solve at a time
  if (loop_closure) return true;
  const std::int64_t since = keyframes_ - last_start_;
  if (since < options_.solve_every_keyframes) return false;
  if (options_.bearings_per_keyframe <= 0.0) return true;
  return static_cast<double>(since) >= static_cast<double>(bearings_in_graph_) / options_.bearings_per_keyframe;
}

void BackEndRunner::start(const slam::FastSlam& filter, bool loop_closure) {
  std::vector<slam::Landmark> map = filter.bestMap();
  smoothing::Graph graph = graph_.build(map);
  bearings_in_graph_ = graph.bearings.size();
  Job job;
  job.started_at_keyframe = keyframes_;
  job.loop_closure = loop_closure;
  job.result = std::async(std::launch::async, solveJob, std::move(graph), std::move(map), options_.solver);
  job_ = std::move(job);
  last_start_ = keyframes_;
  ++stats_.solves_started;
  if (loop_closure) ++stats_.loop_closures;
}

std::optional<BackEndReport> BackEndRunner::collect(slam::FastSlam& filter) {
  if (!job_ || keyframes_ < job_->started_at_keyframe + options_.apply_after_keyframes) return std::nullopt;
  const bool ready = job_->result.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
  if (!ready && !wait_) return std::nullopt;
  if (!ready) ++stats_.waited;
  if (!wait_ && keyframes_ > job_->started_at_keyframe + options_.apply_after_keyframes) ++stats_.late;
  auto [correction, report] = job_->result.get();
  report.loop_closure = job_->loop_closure;
  job_.reset();
  if (!report.ok) {
    ++stats_.solves_failed;
    return report;
  }
  filter.applyCorrection(correction);
  graph_.adoptSolution(report.keyframe_poses, slam::correctionTransform(correction));
  ++stats_.solves_applied;
  stats_.bearings_removed += report.num_removed;
  return report;
}

std::optional<BackEndReport> BackEndRunner::afterStep(slam::FastSlam& filter, smoothing::KeyframeRecord record) {
  ++keyframes_;
  const bool closure = loopClosure(record);
  graph_.add(std::move(record));
  std::optional<BackEndReport> report = collect(filter);
  if (solveDue(closure)) {
    start(filter, closure);
    if (options_.apply_after_keyframes == 0) report = collect(filter);
  }
  return report;
}

}  // namespace omnislam::runtime
