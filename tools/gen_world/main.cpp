// omnislam-gen-world: draws a random ceiling-light world of a family (docs/results/world-families.md) and
// writes it as a world file, and/or writes the feature log the live system would record in it
// (OMNI_FEATURES, ODOMETRY, GROUND_TRUTH_POSE, GROUND_TRUTH_MAP, GROUND_TRUTH_FEATURE_LABELS) from
// the feature-level simulation (common/sim feature_sim.h), without rendering an image.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include "omnislam/config/world_config.h"
#include "omnislam/core/angles.h"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/feature_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/runtime/atomic_file.h"
#include "omnislam/sim/feature_sim.h"
#include "omnislam/sim/world_generator.h"

using namespace omnislam;

namespace {

map_t truthMap(const sim::World& w, int64_t utime, int64_t seq) {
  map_t m{};
  m.utime = utime;
  m.seq = seq;
  m.input_seq = -1;
  for (const sim::Light& L : w.lights) {
    landmark_t l{};
    l.id = L.id;
    for (int i = 0; i < 3; ++i) l.position_m[i] = L.p_LinW_m[i];
    l.kind = feature_t::KIND_CEILING_LIGHT;
    m.landmarks.push_back(l);
  }
  m.num_landmarks = static_cast<int32_t>(m.landmarks.size());
  return m;
}

features_t featuresMsg(const sim::World& w, const sim::SimFrame& f, int64_t utime) {
  features_t m{};
  m.utime = utime;
  m.seq = f.index;
  m.image_seq = f.index;
  m.detector = "ceiling_lights";
  m.camera_position_m[0] = w.camera.mounting.x_m;
  m.camera_position_m[1] = w.camera.mounting.y_m;
  m.camera_position_m[2] = w.camera.mounting.z_m;
  for (const sim::SimFeature& s : f.features) {
    feature_t x{};
    x.kind = feature_t::KIND_CEILING_LIGHT;
    x.azimuth_rad = s.azimuth_rad;
    x.elevation_rad = s.elevation_rad;
    x.has_elevation = true;
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 2; ++c) x.covariance[r][c] = s.covariance_rad2(r, c);
    x.u_px = s.px.x();
    x.v_px = s.px.y();
    x.size_px = s.area_px;
    m.features.push_back(x);
  }
  m.num_features = static_cast<int32_t>(m.features.size());
  return m;
}

feature_labels_t labelsMsg(const sim::SimFrame& f, int64_t utime) {
  feature_labels_t m{};
  m.utime = utime;
  m.seq = f.index;
  m.features_seq = f.index;
  for (const sim::SimFeature& s : f.features) {
    m.landmark_id.push_back(s.light_id >= 0 ? s.light_id : feature_labels_t::UNKNOWN);
    m.source_code.push_back(0);
  }
  m.num_features = static_cast<int32_t>(m.landmark_id.size());
  return m;
}

/// The log, in utime order; at one utime: map (once per simulated second), truth, odometry, features, labels.
void writeLog(const std::string& path, const sim::World& w, const sim::SimRun& run) {
  lcmio::LogWriter out(path, lcmio::LogWriter::Mode::kAtomic);
  const int64_t map_every = std::max<int64_t>(1, std::llround(w.truth_rate_hz));
  size_t next_frame = 0;
  for (size_t k = 0; k < run.steps.size(); ++k) {
    const sim::SimTruthStep& s = run.steps[k];
    const int64_t utime = w.start_utime + static_cast<int64_t>(std::llround(s.t_s * 1e6));
    if (static_cast<int64_t>(k) % map_every == 0)
      out.write(utime, channels::kGroundTruthMap, truthMap(w, utime, static_cast<int64_t>(k) / map_every));
    pose_t p{};
    p.utime = utime;
    p.seq = static_cast<int64_t>(k);
    p.x_m = s.truth.x_m;
    p.y_m = s.truth.y_m;
    p.theta_rad = s.truth.theta_rad;
    p.input_seq = -1;
    out.write(utime, channels::kGroundTruthPose, p);
    odometry_t o{};
    o.utime = utime;
    o.seq = static_cast<int64_t>(k);
    o.x_m = s.odometry.x_m;
    o.y_m = s.odometry.y_m;
    o.theta_rad = s.odometry.theta_rad;
    o.v_mps = s.v_mps;
    o.omega_radps = s.omega_radps;
    out.write(utime, channels::kOdometry, o);
    if (next_frame < run.frames.size() && run.frames[next_frame].truth_step == static_cast<int64_t>(k)) {
      out.write(utime, channels::kOmniFeatures, featuresMsg(w, run.frames[next_frame], utime));
      out.write(utime, channels::kGroundTruthFeatureLabels, labelsMsg(run.frames[next_frame], utime));
      ++next_frame;
    }
  }
  out.commit();
}

/// A JSON string literal (names come from world files: quotes, backslashes and controls escaped).
std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += b;
      continue;
    }
    out += c;
  }
  return out + "\"";
}

std::string num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

/// The largest distance at which any lamp of the world is detected (distinct radius and height).
double perceptionRange_m(const sim::World& w, double min_area_px) {
  std::set<std::pair<double, double>> kinds;
  for (const sim::Light& L : w.lights) kinds.insert({L.radius_m, L.p_LinW_m.z()});
  double r = 0.0;
  for (const auto& [radius, height] : kinds) r = std::max(r, sim::detectionRange_m(w, radius, height, min_area_px));
  return r;
}

/// What the evaluation script needs beside the log: the start pose, the perception range, the lamps
/// seen from >= 3 poses, and the drawn parameters.
std::string infoJson(const sim::World& w, const std::optional<sim::GeneratedParams>& gp, const sim::SimRun* run,
                     const sim::FeatureSimOptions& fo) {
  std::ostringstream j;
  const auto& o = w.trajectory_options;
  j << "{\n  \"world\": " << quoted(w.name) << ",\n  \"lamps\": " << w.lights.size()
    << ",\n  \"start_x_m\": " << num(o.start.x_m) << ",\n  \"start_y_m\": " << num(o.start.y_m)
    << ",\n  \"start_theta_deg\": " << num(rad2deg(o.start.theta_rad))
    << ",\n  \"min_elevation_deg\": " << num(90.0 - rad2deg(w.camera.intrinsics.max_zenith_rad))
    << ",\n  \"perception_max_range_m\": " << num(perceptionRange_m(w, fo.min_area_px))
    << ",\n  \"image_rate_hz\": " << num(w.image_rate_hz) << ",\n  \"truth_rate_hz\": " << num(w.truth_rate_hz);
  if (gp)
    j << ",\n  \"family\": \"" << sim::worldFamilyName(gp->family) << "\",\n  \"seed\": " << gp->seed
      << ",\n  \"hall_x_m\": " << num(gp->hall_x_m) << ",\n  \"hall_y_m\": " << num(gp->hall_y_m)
      << ",\n  \"spacing_x_m\": " << num(gp->spacing_x_m) << ",\n  \"spacing_y_m\": " << num(gp->spacing_y_m)
      << ",\n  \"ceiling_min_m\": " << num(gp->ceiling_min_m) << ",\n  \"ceiling_max_m\": " << num(gp->ceiling_max_m)
      << ",\n  \"lamps_missing\": " << gp->lamps_missing << ",\n  \"lamps_extra\": " << gp->lamps_extra
      << ",\n  \"close_pairs\": " << gp->close_pairs << ",\n  \"loops\": " << gp->loops
      << ",\n  \"path_m\": " << num(gp->path_m);
  if (run) {
    std::map<int64_t, int> seen;
    int64_t features = 0, clutter = 0;
    for (const auto& f : run->frames)
      for (const auto& s : f.features) {
        ++features;
        if (s.light_id < 0) ++clutter;
        else ++seen[s.light_id];
      }
    int seen3 = 0;
    for (const auto& [id, n] : seen) seen3 += n >= 3 ? 1 : 0;
    j << ",\n  \"frames\": " << run->frames.size() << ",\n  \"features\": " << features
      << ",\n  \"clutter_features\": " << clutter << ",\n  \"lamps_seen\": " << seen.size()
      << ",\n  \"lamps_seen_3\": " << seen3 << ",\n  \"duration_s\": " << num(run->steps.back().t_s)
      << ",\n  \"odometry_scale_error\": " << num(run->odometry_scale_error)
      << ",\n  \"odometry_heading_drift_rad_per_m\": " << num(run->odometry_heading_drift_rad_per_m);
  }
  if (fo.kidnap)
    j << ",\n  \"kidnap_at_s\": " << num(fo.kidnap->at_s) << ",\n  \"kidnap_to_s\": " << num(fo.kidnap->to_s);
  j << "\n}\n";
  return j.str();
}

/// Draws a world of the family (written to out_world unless empty) into `world`, read back from
/// its YAML (what the file says); its drawn parameters.
sim::GeneratedParams drawWorld(sim::WorldFamily fam, const std::string& family, uint64_t seed, double rate_hz,
                               const std::string& out_world, sim::World& world) {
  sim::GeneratorOptions go;
  go.image_rate_hz = rate_hz;
  const sim::GeneratedWorld g = sim::generateWorld(fam, seed, go);
  const std::string yaml = sim::worldToYaml(
      g.world, {"Generated by omnislam-gen-world --family " + family + " --seed " + std::to_string(seed) +
                " --rate-hz " + num(rate_hz) + " (docs/results/world-families.md); schema: docs/user/world-file.md"});
  if (!out_world.empty()) runtime::writeFileAtomically(out_world, yaml.data(), yaml.size());
  world = config::parseWorld(config::Node::loadString(yaml, "generated world"));
  return g.params;
}

/// --kidnap-at-s and --kidnap-to-s (both or neither) into fo.kidnap.
void addKidnapOptions(CLI::App& cli, sim::FeatureSimOptions& fo) {
  const auto kidnap = [&fo]() -> sim::FeatureSimOptions::Kidnap& {
    return fo.kidnap ? *fo.kidnap : fo.kidnap.emplace();
  };
  auto* at = cli.add_option_function<double>(
                    "--kidnap-at-s", [kidnap](double s) { kidnap().at_s = s; },
                    "a kidnap: at this time of the drive [s] the robot is carried (the odometry does not see it) ...")
                 ->check(app::FiniteRange(0.0, 1e6));
  cli.add_option_function<double>(
         "--kidnap-to-s", [kidnap](double s) { kidnap().to_s = s; },
         "... to where the drive is at this time [s], and drives on from there")
      ->check(app::FiniteRange(0.0, 1e6))
      ->needs(at);
  at->needs("--kidnap-to-s");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{
      "omnislam-gen-world: random ceiling-light worlds and their feature logs (docs/results/world-families.md)"};
  std::string family, world_in, out_world, out_log, out_info;
  uint64_t seed = 1, odometry_seed = 0, detector_seed = 0;
  double rate_hz = 1.0;
  sim::FeatureSimOptions fo;
  cli.add_option("--family", family, "halls | irregular | corridors: draw a world of this family");
  auto* world_opt = cli.add_option("--world", world_in, "or: an existing lights world file (config/worlds/*.yaml)");
  cli.add_option("--seed", seed, "world seed (also the sensors' seeds unless given)")->check(app::SeedRange());
  cli.add_option("--odometry-seed", odometry_seed, "odometry noise seed (0 = --seed)")->check(app::SeedRange());
  cli.add_option("--detector-seed", detector_seed, "detector noise seed (0 = derived from --seed)")
      ->check(app::SeedRange());
  cli.add_option("--rate-hz", rate_hz, "feature frame rate of a drawn world, Hz")
      ->check(app::FiniteRange(0.01, 100.0))
      ->excludes(world_opt);
  cli.add_option("--out-world", out_world, "write the drawn world file here")->excludes(world_opt);
  cli.add_option("--out-log", out_log, "write the feature log here");
  cli.add_option("--out-info", out_info, "write the start pose, perception range, lamps seen (JSON) here");
  cli.add_option("--pixel-sigma-px", fo.pixel_sigma_px, "centroid noise, px")->check(app::FiniteRange(1e-6, 100.0));
  cli.add_option("--min-area-px", fo.min_area_px, "smallest detected blob, px")->check(app::FiniteRange(0.0, 1e6));
  addKidnapOptions(cli, fo);
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return app::runMain("omnislam-gen-world", [&]() -> int {
    if (family.empty() == world_in.empty() || (out_world.empty() && out_log.empty() && out_info.empty())) {
      std::cerr << "omnislam-gen-world: give exactly one of --family and --world, and at least one of --out-world, "
                   "--out-log, --out-info"
                << std::endl;
      return app::kBadConfig;
    }
    for (const auto& [path, flag] :
         {std::pair{out_world, "--out-world"}, {out_log, "--out-log"}, {out_info, "--out-info"}})
      if (!path.empty()) lcmio::requireWritableFile(path, flag);
    std::optional<sim::GeneratedParams> params;
    sim::World world;
    if (!family.empty()) {
      const auto fam = sim::parseWorldFamily(family);
      if (!fam) {
        std::cerr << "omnislam-gen-world: --family must be halls, irregular or corridors, got '" << family << "'"
                  << std::endl;
        return app::kBadConfig;
      }
      params = drawWorld(*fam, family, seed, rate_hz, out_world, world);
    } else {
      world = config::loadWorld(world_in);
    }
    std::unique_ptr<sim::SimRun> run;
    if (!out_log.empty() || !out_info.empty())
      run = std::make_unique<sim::SimRun>(sim::simulateFeatures(
          world, odometry_seed ? odometry_seed : seed, detector_seed ? detector_seed : sim::deriveSeed(seed, 2), fo));
    if (!out_log.empty()) writeLog(out_log, world, *run);
    if (!out_info.empty()) {
      const std::string info = infoJson(world, params, run.get(), fo);
      runtime::writeFileAtomically(out_info, info.data(), info.size());
    }
    std::cerr << "omnislam-gen-world: '" << world.name << "': " << world.lights.size() << " lamps"
              << (run ? ", " + std::to_string(run->frames.size()) + " frames" : std::string()) << std::endl;
    return app::kOk;
  });
}
