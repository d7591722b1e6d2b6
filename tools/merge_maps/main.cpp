// omnislam-merge-maps: merges two saved maps of one building made in separate sessions, their
// relative pose unknown (issue 56, item 4): the lamp constellations registered (slam::registerMaps),
// then one joint solve of the transform and the fused lamps (smoothing::mergeMaps); the merged map is
// in A's frame. A map of another building, or an ambiguous match (a symmetric grid), is refused.
//   omnislam-merge-maps A.yaml B.yaml --out M.yaml [--gate_probability 0.99 ...]
// Prints T_AB (B's frame in A's), the inliers and the decision. Exit codes: 0 merged; 3 refused
// (one line naming why); 2 a bad flag or a map file loadMap refuses; 1 a failure to write.
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>

#include "omnislam/core/slam/options_table.h"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/runtime/map_file.h"
#include "omnislam/smoothing/map_merge.h"

using namespace omnislam;

namespace {

constexpr int kRefused = 3;

/// One flag per row of the options table (--key VALUE), its range checked by validate().
void addRegistrationFlags(CLI::App& cli, slam::MapRegistrationOptions& o) {
  for (const auto& f : slam::options::mapRegistrationFields()) {
    const std::string help = std::string(f.doc) + " (default " + slam::options::valueText(f, o) + ", range " +
                             slam::options::rangeText(f) + ")";
    if (f.kind == slam::options::Kind::kReal) cli.add_option(std::string("--") + f.key, o.*(f.real), help);
    if (f.kind == slam::options::Kind::kInt) cli.add_option(std::string("--") + f.key, o.*(f.integer), help);
  }
}

void printTransform(const char* what, const slam::RegisteredTransform& t) {
  std::printf(
      "%s: T_AB = (%.4f m, %.4f m, %.4f deg), sigma (%.4f m, %.4f m, %.4f deg); %zu lamps matched, %d in A's area\n",
      what, t.T_AB.x_m, t.T_AB.y_m, t.T_AB.theta_rad * 180.0 / M_PI, std::sqrt(t.cov(0, 0)), std::sqrt(t.cov(1, 1)),
      std::sqrt(t.cov(2, 2)) * 180.0 / M_PI, t.inliers.size(), t.in_area);
}

int mergeFiles(const std::string& path_A, const std::string& path_B, const std::string& out,
               const slam::MapRegistrationOptions& o) {
  const std::string bad = o.validate();
  if (!bad.empty()) throw std::invalid_argument("--" + bad.substr(0, bad.find(' ')) + ": " + bad);
  if (!out.empty()) lcmio::requireWritableFile(out, "--out");  // before the work, not after it
  const runtime::SavedMap A = runtime::loadMap(path_A), B = runtime::loadMap(path_B);
  std::printf("A: %s, %zu landmarks; B: %s, %zu landmarks\n", path_A.c_str(), A.landmarks.size(), path_B.c_str(),
              B.landmarks.size());
  const slam::MapRegistration reg = slam::registerMaps(A.landmarks, B.landmarks, o);
  if (reg.decision != slam::RegistrationDecision::kInvalidInput &&
      reg.decision != slam::RegistrationDecision::kNoOverlap)
    printTransform("registration", reg.best);
  if (!reg.second.inliers.empty()) printTransform("best other transform", reg.second);
  if (reg.best.inliers.empty()) std::printf("decision: %s\n", slam::registrationDecisionName(reg.decision));
  else
    std::printf("decision: %s (count log-likelihood ratio %.1f, other %.1f; chance P %.3g; self matches %d)\n",
                slam::registrationDecisionName(reg.decision), reg.best.count_log_likelihood,
                reg.second.count_log_likelihood, reg.chance_tail, reg.self_matches);
  if (reg.decision != slam::RegistrationDecision::kAccepted) {
    std::cerr << "omnislam-merge-maps: refused: " << reg.reason << std::endl;
    return kRefused;
  }
  const smoothing::MergedMap m = smoothing::mergeMaps(A.landmarks, B.landmarks, reg.best, o.extra_sigma_m);
  slam::RegisteredTransform solved = reg.best;
  solved.T_AB = m.T_AB, solved.cov = m.cov_T;
  printTransform("joint solve", solved);
  std::printf("merged: %zu landmarks (%d fused, %d of A alone, %d of B moved); %s\n", m.landmarks.size(), m.fused,
              m.kept_A, m.moved_B, m.message.c_str());
  if (!out.empty()) {
    runtime::saveMapAtomically(runtime::SavedMap{std::max(A.utime, B.utime), m.landmarks}, out);
    std::printf("written: %s\n", out.c_str());
  }
  return app::kOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-merge-maps: merge two saved maps of one building (docs/design/global-localisation.md)"};
  std::string path_A, path_B, out;
  slam::MapRegistrationOptions o;
  cli.add_option("A", path_A, "map A (its frame is the merged map's)")->required();
  cli.add_option("B", path_B, "map B (a separate session, its frame unknown)")->required();
  cli.add_option("--out", out, "write the merged map here (atomically); without it only the registration is printed");
  addRegistrationFlags(cli, o);
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return app::runMain("omnislam-merge-maps", [&]() { return mergeFiles(path_A, path_B, out, o); });
}
