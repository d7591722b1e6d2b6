// The FastSLAM filter's complete state to and from bytes (checkpoints), bit-exact: see
// FastSlam::saveState / loadState in fastslam.h. Shared storage (maps, cells, candidates) is written
// once in tables and referenced by index, so the size grows with what the particles hold, not with
// M times it, and a loaded filter shares what the saved one shared.
#include <map>
#include <string>

#include "omnislam/core/slam/fastslam.h"
#include "omnislam/core/slam/landmark_codec.h"

namespace omnislam::slam {

namespace {

constexpr std::uint32_t kSectionTag = 0x4D4C5346u;  // "FSLM" little-endian
constexpr std::uint32_t kSectionVersion = 1;
constexpr std::size_t kMaxItems = std::size_t{1} << 28;  // any table or list

void putPose(ByteWriter& w, const Pose2& p) {
  w.f64(p.x_m);
  w.f64(p.y_m);
  w.f64(p.theta_rad);
}
Pose2 getPose(ByteReader& r) {
  Pose2 p;
  p.x_m = r.f64("pose.x_m");
  p.y_m = r.f64("pose.y_m");
  p.theta_rad = r.f64("pose.theta_rad");
  return p;
}

template <class M>
void putMatrix(ByteWriter& w, const M& m) {  // row-major
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) w.f64(m(i, j));
}
template <class M>
void getMatrix(ByteReader& r, M& m, const char* what) {
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) m(i, j) = r.f64(what);
}

void putDescriptor(ByteWriter& w, const ColourDescriptor& d) {
  w.boolean(d.valid);
  for (float v : d.rgb) w.f32(v);
}
ColourDescriptor getDescriptor(ByteReader& r) {
  ColourDescriptor d;
  d.valid = r.boolean("descriptor.valid");
  for (float& v : d.rgb) v = r.f32("descriptor.rgb");
  return d;
}

LandmarkKind getKind(ByteReader& r) {
  const std::uint8_t k = r.u8("landmark kind");
  if (k > 1) throw StateFormatError("landmark kind " + std::to_string(k) + " is not 0 (point) or 1 (vertical line)");
  return static_cast<LandmarkKind>(k);
}

template <class Dyn>
void putDynamic(ByteWriter& w, const Dyn& m) {
  w.u8(static_cast<std::uint8_t>(m.rows()));
  w.u8(static_cast<std::uint8_t>(m.cols()));
  putMatrix(w, m);
}
template <class Dyn>
void getDynamic(ByteReader& r, Dyn& m, int max_rows, int max_cols, const char* what) {
  const int rows = r.u8(what), cols = r.u8(what);
  if (rows < 0 || rows > max_rows || cols < 0 || cols > max_cols)
    throw StateFormatError(std::string(what) + ": size " + std::to_string(rows) + " x " + std::to_string(cols) +
                           " out of range");
  m.resize(rows, cols);
  getMatrix(r, m, what);
}

void putCandidate(ByteWriter& w, const Candidate& c) {
  w.u8(static_cast<std::uint8_t>(c.kind));
  putDescriptor(w, c.descriptor);
  w.u64(c.observations.size());
  for (const CandidateObservation& o : c.observations) {
    putPose(w, o.T_WtoR);
    putMatrix(w, o.p_CinR_m);
    putDynamic(w, o.z);
    putDynamic(w, o.Q);
    putMatrix(w, o.p_CinW_m);
    putMatrix(w, o.dir_W);
    w.f64(o.cos_theta);
    w.f64(o.sin_theta);
  }
  w.i32(c.num_associated);
  w.i32(c.counter);
  w.i32(c.consecutive_misses);
  w.boolean(c.has_estimate);
  putMatrix(w, c.estimate_W_m);
  putMatrix(w, c.estimate_cov_m2);
}
std::shared_ptr<const Candidate> getCandidate(ByteReader& r) {
  auto c = std::make_shared<Candidate>();
  c->kind = getKind(r);
  c->descriptor = getDescriptor(r);
  c->observations.resize(r.count("candidate observations", kMaxItems, 8 * 14));
  for (CandidateObservation& o : c->observations) {
    o.T_WtoR = getPose(r);
    getMatrix(r, o.p_CinR_m, "observation.p_CinR_m");
    getDynamic(r, o.z, 2, 1, "observation.z");
    getDynamic(r, o.Q, 2, 2, "observation.Q");
    getMatrix(r, o.p_CinW_m, "observation.p_CinW_m");
    getMatrix(r, o.dir_W, "observation.dir_W");
    o.cos_theta = r.f64("observation.cos_theta");
    o.sin_theta = r.f64("observation.sin_theta");
  }
  c->num_associated = r.i32("candidate.num_associated");
  c->counter = r.i32("candidate.counter");
  c->consecutive_misses = r.i32("candidate.consecutive_misses");
  c->has_estimate = r.boolean("candidate.has_estimate");
  getMatrix(r, c->estimate_W_m, "candidate.estimate_W_m");
  getMatrix(r, c->estimate_cov_m2, "candidate.estimate_cov_m2");
  return c;
}

void putDoubles(ByteWriter& w, const std::vector<double>& v) {
  w.u64(v.size());
  for (double x : v) w.f64(x);
}
std::vector<double> getDoubles(ByteReader& r, std::size_t expected, const char* what) {
  std::vector<double> v(r.count(what, kMaxItems, 8));
  if (v.size() != expected)
    throw StateFormatError(std::string(what) + ": " + std::to_string(v.size()) + " values for " +
                           std::to_string(expected) + " particles");
  for (double& x : v) x = r.f64(what);
  return v;
}

/// Index of `key` in a table being built (first use appends it).
template <class K>
std::uint64_t indexOf(std::map<K, std::uint64_t>& index, std::vector<K>& table, const K& key) {
  const auto [it, fresh] = index.emplace(key, table.size());
  if (fresh) table.push_back(key);
  return it->second;
}

std::uint64_t getIndex(ByteReader& r, std::size_t table_size, const char* what) {
  const std::uint64_t i = r.u64(what);
  if (i >= table_size)
    throw StateFormatError(std::string(what) + ": index " + std::to_string(i) + " beyond the table of " +
                           std::to_string(table_size));
  return i;
}

void checkSame(bool same, const char* key, const std::string& saved, const std::string& now) {
  if (!same)
    throw StateFormatError(std::string("written with filter.") + key + " = " + saved + ", the options now say " + now);
}

/// The particles with their shared storage: tables of cells, maps and candidates (in first-use
/// order, so deterministic), each written once, then per particle its pose, weight, map, scale sums
/// and candidates by index.
void writeParticles(ByteWriter& w, const std::vector<Particle>& particles) {
  // Tables of shared storage, in first-use order (deterministic: particles in order).
  std::map<const void*, std::uint64_t> map_index, cell_index, cand_index;
  std::vector<const void*> maps, cells, cands;
  std::vector<const LandmarkMap*> map_of;  // per map table entry
  std::vector<const LandmarkMap::Cell*> cell_of;
  std::vector<const Candidate*> cand_of;
  for (const Particle& p : particles) {
    const void* root = p.map.rootNode() ? static_cast<const void*>(p.map.rootNode()) : static_cast<const void*>(&p.map);
    if (indexOf(map_index, maps, root) == map_of.size()) map_of.push_back(&p.map);
    for (const auto& c : p.candidates)
      if (indexOf(cand_index, cands, static_cast<const void*>(c.get())) == cand_of.size()) cand_of.push_back(c.get());
  }
  std::vector<std::vector<std::pair<std::uint64_t, std::uint64_t>>> map_cells(map_of.size());
  for (std::size_t m = 0; m < map_of.size(); ++m) {
    for (const auto& [key, cell] : map_of[m]->cells()) {
      const std::uint64_t ci = indexOf(cell_index, cells, static_cast<const void*>(cell.get()));
      if (ci == cell_of.size()) cell_of.push_back(cell.get());
      map_cells[m].emplace_back(key, ci);
    }
  }
  w.u64(cell_of.size());
  for (const LandmarkMap::Cell* c : cell_of) {
    w.u64(c->landmarks.size());
    for (const Landmark& l : c->landmarks) putLandmark(w, l);
  }
  w.u64(map_cells.size());
  for (const auto& mc : map_cells) {
    w.u64(mc.size());
    for (const auto& [key, ci] : mc) {
      w.u64(key);
      w.u64(ci);
    }
  }
  w.u64(cand_of.size());
  for (const Candidate* c : cand_of) putCandidate(w, *c);

  w.u64(particles.size());
  for (const Particle& p : particles) {
    putPose(w, p.pose);
    w.f64(p.log_weight);
    const void* root = p.map.rootNode() ? static_cast<const void*>(p.map.rootNode()) : static_cast<const void*>(&p.map);
    w.u64(map_index.at(root));
    w.f64(p.scale_path_m);
    w.f64(p.scale_odometry_m);
    w.u64(p.candidates.size());
    for (const auto& c : p.candidates) w.u64(cand_index.at(c.get()));
  }
}

/// What writeParticles wrote, for M particles and maps of this cell size.
std::vector<Particle> readParticles(ByteReader& r, double cell, std::size_t M) {
  std::vector<std::shared_ptr<const LandmarkMap::Cell>> cells(r.count("cells", kMaxItems, 8));
  for (auto& c : cells) {
    auto cell = std::make_shared<LandmarkMap::Cell>();
    cell->landmarks.resize(r.count("landmarks of a cell", kMaxItems, 135));
    for (Landmark& l : cell->landmarks) l = getLandmark(r);
    c = std::move(cell);
  }
  std::vector<LandmarkMap> maps;
  const std::size_t num_maps = r.count("maps", kMaxItems, 8);
  maps.reserve(num_maps);
  for (std::size_t i = 0; i < num_maps; ++i) {
    std::vector<std::pair<std::uint64_t, std::shared_ptr<const LandmarkMap::Cell>>> mc(
        r.count("cells of a map", kMaxItems, 16));
    for (auto& [key, c] : mc) {
      key = r.u64("cell key");
      c = cells[getIndex(r, cells.size(), "cell")];
    }
    try {
      maps.push_back(LandmarkMap::fromCells(cell, mc));
    } catch (const std::invalid_argument& e) {
      throw StateFormatError(e.what());
    }
  }
  std::vector<std::shared_ptr<const Candidate>> cands(r.count("candidates", kMaxItems, 16));
  for (auto& c : cands) c = getCandidate(r);

  std::vector<Particle> particles(r.count("particles", kMaxItems, 56));
  if (particles.size() != M)
    throw StateFormatError("particles: " + std::to_string(particles.size()) + " for M = " + std::to_string(M));
  for (Particle& p : particles) {
    p.pose = getPose(r);
    p.log_weight = r.f64("log_weight");
    p.map = maps[getIndex(r, maps.size(), "map")];
    p.scale_path_m = r.f64("scale_path_m");
    p.scale_odometry_m = r.f64("scale_odometry_m");
    p.candidates.resize(r.count("candidates of a particle", kMaxItems, 8));
    for (auto& c : p.candidates) c = cands[getIndex(r, cands.size(), "candidate")];
  }
  return particles;
}

}  // namespace

void putLandmark(ByteWriter& w, const Landmark& l) {
  w.u64(l.id);
  putMatrix(w, l.p_LinW_m);
  putMatrix(w, l.cov_LinW_m2);
  w.i32(l.counter);
  w.u8(static_cast<std::uint8_t>(l.type));
  w.u8(static_cast<std::uint8_t>(l.kind));
  putDescriptor(w, l.descriptor);
}
Landmark getLandmark(ByteReader& r) {
  Landmark l;
  l.id = r.u64("landmark.id");
  getMatrix(r, l.p_LinW_m, "landmark.p_LinW_m");
  getMatrix(r, l.cov_LinW_m2, "landmark.cov_LinW_m2");
  l.counter = r.i32("landmark.counter");
  const std::uint8_t type = r.u8("landmark.type");
  if (type != 1 && type != 2) throw StateFormatError("landmark type " + std::to_string(type) + " is not 1 or 2");
  l.type = static_cast<LandmarkType>(type);
  l.kind = getKind(r);
  l.descriptor = getDescriptor(r);
  return l;
}

void FastSlam::saveState(ByteWriter& w) const {
  w.u32(kSectionTag);
  w.u32(kSectionVersion);
  // Options the layout depends on.
  w.i32(options_.num_particles);
  w.f64(options_.map_cell_size_m);
  w.u8(static_cast<std::uint8_t>(options_.proposal.index()));  // 0 FastSLAM 2.0, 1 FastSLAM 1.0
  w.u8(static_cast<std::uint8_t>(options_.association));
  w.boolean(options_.update_map);
  w.boolean(options_.odometry_scale_correction);
  // Scalars.
  w.str(rng_.state());
  w.f64(ess_);
  w.i32(best_index_);
  w.u64(next_landmark_id_);
  w.u64(num_steps_);
  putMatrix(w, last_p_CinR_m_);
  putMatrix(w, scale_anchor_xy_);
  w.boolean(scale_anchored_);
  putDoubles(w, weights_);
  w.u64(poses_before_resampling_.size());
  for (const Pose2& p : poses_before_resampling_) putPose(w, p);
  putDoubles(w, weights_before_resampling_);

  writeParticles(w, particles_);
}

FastSlam FastSlam::loadState(const FastSlamOptions& options, ByteReader& r) {
  FastSlam f(options, 0);
  const std::uint32_t tag = r.u32("filter section tag");
  if (tag != kSectionTag) throw StateFormatError("no filter state where one was expected (section tag)");
  const std::uint32_t version = r.u32("filter section version");
  if (version != kSectionVersion)
    throw StateFormatError("filter state version " + std::to_string(version) + ", this program reads " +
                           std::to_string(kSectionVersion));
  const FastSlamOptions& o = f.options_;
  const std::int32_t m = r.i32("num_particles");
  checkSame(m == o.num_particles, "particles", std::to_string(m), std::to_string(o.num_particles));
  const double cell = r.f64("map_cell_size_m");
  checkSame(cell == o.map_cell_size_m, "map_cell_size_m", std::to_string(cell), std::to_string(o.map_cell_size_m));
  const int proposal = r.u8("proposal"), association = r.u8("association");
  checkSame(proposal == static_cast<int>(o.proposal.index()), "proposal", std::to_string(proposal),
            std::to_string(o.proposal.index()));
  checkSame(association == static_cast<int>(o.association), "association", std::to_string(association),
            std::to_string(static_cast<int>(o.association)));
  const bool update_map = r.boolean("update_map"), scale = r.boolean("odometry_scale_correction");
  checkSame(update_map == o.update_map, "update_map (localisation only)", std::to_string(update_map),
            std::to_string(o.update_map));
  checkSame(scale == o.odometry_scale_correction, "odometry_scale_correction", std::to_string(scale),
            std::to_string(o.odometry_scale_correction));

  if (!f.rng_.setState(r.str("generator state", 1 << 16)))
    throw StateFormatError("the generator state is not a std::mt19937_64 state");
  f.ess_ = r.f64("ess");
  f.best_index_ = r.i32("best_index");
  if (f.best_index_ < 0 || f.best_index_ >= m)
    throw StateFormatError("best particle index " + std::to_string(f.best_index_) + " out of range");
  f.next_landmark_id_ = r.u64("next_landmark_id");
  f.num_steps_ = r.u64("num_steps");
  getMatrix(r, f.last_p_CinR_m_, "last_p_CinR_m");
  getMatrix(r, f.scale_anchor_xy_, "scale_anchor_xy");
  f.scale_anchored_ = r.boolean("scale_anchored");
  const std::size_t M = static_cast<std::size_t>(m);
  f.weights_ = getDoubles(r, M, "weights");
  f.poses_before_resampling_.resize(r.count("poses before resampling", kMaxItems, 24));
  if (f.poses_before_resampling_.size() != M) throw StateFormatError("poses before resampling: not one per particle");
  for (Pose2& p : f.poses_before_resampling_) p = getPose(r);
  f.weights_before_resampling_ = getDoubles(r, M, "weights before resampling");

  f.particles_ = readParticles(r, cell, M);
  return f;
}

}  // namespace omnislam::slam
