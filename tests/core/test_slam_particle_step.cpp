// The public per-particle step (particle_step.h): with the filter's association it is FastSlam's step
// (one particle, so no resampling choice intervenes); an association hook decides the pose the
// particle ends at and sees FastSLAM 1.0's sampled pose; a birth hook sees the step's newborn.
#include <gtest/gtest.h>

#include <variant>

#include "omnislam/core/slam/fastslam.h"
#include "omnislam/core/slam/particle_step.h"
#include "slam_scenarios.h"

using namespace omnislam;
using namespace omnislam::slam;

namespace {

// processParticle driven by hand over the hall's frames with `associate`, as FastSlam drives it.
struct ByHand {
  FastSlamOptions o;
  stages::FilterVariant variant;
  Rng rng;
  std::uint64_t next_id = 0;
  std::vector<double> buffer;
  Particle p;
  Eigen::Vector3d p_CinR_m = o.perception.default_p_CinR_m;
  ByHand(const FastSlamOptions& opt, std::uint64_t seed, const Pose2& start)
      : o(opt), variant(filterVariantOf(opt)), rng(seed), p{start, 0.0, LandmarkMap(opt.map_cell_size_m), {}} {}
  ParticleStepInfo step(const Pose2& prev, const Pose2& now, const std::vector<BearingMeasurement>& z,
                        const AssociationHook& associate, const BirthHook& birth = {}) {
    std::vector<char> refused;
    const auto Z = stages::prepareMeasurements(z, o.inflate_azimuth_near_zenith, o.p_new_mahalanobis_sq, refused);
    if (!Z.empty()) p_CinR_m = Z.front().p_CinR_m;
    const StepInput in{odometryIncrement(prev, now), Z, p_CinR_m, std::nullopt};
    ParticleRng particle_rng = ParticleRng::drawFrom(rng);  // as FastSlam: the particle's slice
    StepState state{particle_rng, next_id, buffer};
    const ParticleStepInfo info = processParticle(p, o, variant, in, state, associate, birth);
    rng.uniform01();  // FastSlam's resampling draw (one particle: always resampled)
    return info;
  }
};

}  // namespace

TEST(slam_ParticleStep, WithTheFilterAssociationItIsFastSlamsStep) {
  for (const bool fs1 : {false, true}) {
    FastSlamOptions o;
    o.num_particles = 1;
    if (fs1) o.proposal = FastSlam1Proposal{};
    const auto frames = scenarios::simulateHall(11);
    FastSlam f(o, 5);
    f.initialise(frames[0].truth);
    ByHand h(o, 5, frames[0].truth);
    const AssociationHook filter = [&](const AssociationInput& in) {
      return associateAsFilter(h.variant, o.update_map, o.perception, in);
    };
    int born = 0;
    for (std::size_t k = 1; k < frames.size(); ++k) {
      const StepResult r = f.step(frames[k - 1].odom, frames[k].odom, frames[k].z);
      const ParticleStepInfo info = h.step(frames[k - 1].odom, frames[k].odom, frames[k].z, filter);
      ASSERT_EQ(f.particles()[0].pose.vec(), h.p.pose.vec()) << "step " << k;
      ASSERT_EQ(f.particles()[0].map.size(), h.p.map.size()) << "step " << k;
      ASSERT_EQ(r.num_associated, info.num_associated) << "step " << k;
      born += info.num_initialised;
    }
    EXPECT_GT(born, 0) << "the comparison covered initialisations";
  }
}

TEST(slam_ParticleStep, TheAssociationHookChoosesWhereTheParticleEnds) {
  const auto frames = scenarios::simulateHall(12);
  for (const bool fs1 : {false, true}) {
    FastSlamOptions o;
    if (fs1) o.proposal = FastSlam1Proposal{};
    ByHand h(o, 3, frames[0].truth);
    int calls = 0;
    const Pose2 chosen{1.0, 2.0, 0.3};
    const AssociationHook none = [&](const AssociationInput& in) {
      ++calls;
      EXPECT_EQ(in.x_sampled.has_value(), fs1);  // FastSLAM 1.0 sampled x_t before the association
      stages::HierarchicalAssociation a;
      a.level1.landmark_of_measurement.assign(in.Z.size(), -1);
      a.x_t = chosen;
      return a;
    };
    std::vector<std::size_t> newborn_sizes;
    const BirthHook birth = [&](std::vector<Landmark>& newborn) { newborn_sizes.push_back(newborn.size()); };
    h.step(frames[0].odom, frames[1].odom, frames[1].z, none, birth);
    EXPECT_EQ(calls, 1);
    EXPECT_EQ(h.p.pose.vec(), chosen.vec());
    EXPECT_EQ(h.p.map.size(), 0u);
    EXPECT_EQ(newborn_sizes, std::vector<std::size_t>{0u});  // called once, with nothing born
  }
}
