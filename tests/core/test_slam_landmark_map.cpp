// Tests of the copy-on-write landmark map: content semantics against a plain reference, spatial
// queries, and storage sharing (a copy shares everything, an edit separates only what it touches).
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>

#include "omnislam/core/slam/landmark_map.h"

namespace {

using namespace omnislam::slam;

Landmark makeLandmark(std::uint64_t id, double x, double y, double z = 6.5) {
  Landmark l;
  l.id = id;
  l.p_LinW_m = Eigen::Vector3d(x, y, z);
  l.counter = static_cast<int>(id % 7);
  return l;
}

std::map<std::uint64_t, Landmark> asMap(const LandmarkMap& m) {
  std::map<std::uint64_t, Landmark> out;
  for (const auto& l : m.landmarks()) EXPECT_TRUE(out.emplace(l.id, l).second) << "duplicate id " << l.id;
  return out;
}

LandmarkMap::Ref refOf(const LandmarkMap& m, std::uint64_t id) {
  std::vector<LandmarkMap::Ref> refs;
  m.collectAll(refs);
  for (const auto& r : refs) {
    if (r.landmark->id == id) return r;
  }
  ADD_FAILURE() << "id not found " << id;
  return {};
}

TEST(slam_LandmarkMap, InsertEditEraseAgainstReference) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-60.0, 60.0);
  LandmarkMap m(4.0);
  std::map<std::uint64_t, Landmark> ref;
  std::uint64_t next = 0;
  for (int step = 0; step < 300; ++step) {
    std::vector<LandmarkMap::Edit> edits;
    std::vector<Landmark> inserts;
    std::vector<LandmarkMap::Ref> all;
    m.collectAll(all);
    std::vector<char> used(all.size(), 0);
    for (int e = 0; e < 5 && !all.empty(); ++e) {
      const std::size_t k = rng() % all.size();
      if (used[k]) continue;
      used[k] = 1;
      LandmarkMap::Edit ed;
      ed.ref = all[k];
      ed.erase = rng() % 4 == 0;
      ed.value = *all[k].landmark;
      // Small moves (same cell mostly) and occasional jumps to another cell.
      ed.value.p_LinW_m.x() += (rng() % 5 == 0) ? u(rng) : 0.01;
      ed.value.counter += 1;
      if (ed.erase) {
        ref.erase(ed.value.id);
      } else {
        ref[ed.value.id] = ed.value;
      }
      edits.push_back(ed);
    }
    for (int i = 0; i < 3; ++i) {
      inserts.push_back(makeLandmark(next++, u(rng), u(rng)));
      ref[inserts.back().id] = inserts.back();
    }
    m.apply(edits, inserts);
    ASSERT_EQ(m.size(), ref.size());
  }
  const auto got = asMap(m);
  ASSERT_EQ(got.size(), ref.size());
  for (const auto& [id, l] : ref) {
    ASSERT_TRUE(got.count(id));
    EXPECT_EQ(got.at(id).p_LinW_m, l.p_LinW_m);
    EXPECT_EQ(got.at(id).counter, l.counter);
  }
  // Every landmark sits in the cell of its mean.
  std::vector<LandmarkMap::Ref> all;
  m.collectAll(all);
  for (const auto& r : all) EXPECT_EQ(r.cell_key, m.cellKeyOf(r.landmark->p_LinW_m.x(), r.landmark->p_LinW_m.y()));
}

TEST(slam_LandmarkMap, CollectNearIsSupersetOfDisc) {
  LandmarkMap m(4.0);
  std::uint64_t id = 0;
  for (int i = -30; i <= 30; ++i) {
    for (int j = -30; j <= 30; ++j) m.insert(makeLandmark(id++, 4.5 * i + 0.3, 4.5 * j - 0.2));
  }
  for (double reach : {0.5, 9.5, 30.0}) {
    std::vector<LandmarkMap::Ref> near;
    m.collectNear(3.0, -7.0, reach, near);
    std::size_t in_disc = 0, found_in_disc = 0;
    for (const auto& l : m.landmarks()) {
      if (std::hypot(l.p_LinW_m.x() - 3.0, l.p_LinW_m.y() + 7.0) <= reach) ++in_disc;
    }
    for (const auto& r : near) {
      EXPECT_LE(std::abs(r.landmark->p_LinW_m.x() - 3.0), reach + 4.0);
      if (std::hypot(r.landmark->p_LinW_m.x() - 3.0, r.landmark->p_LinW_m.y() + 7.0) <= reach) ++found_in_disc;
    }
    EXPECT_EQ(found_in_disc, in_disc) << reach;
    EXPECT_LT(near.size(), m.size() / 4) << "query must not return the whole map";
  }
  std::vector<LandmarkMap::Ref> all;
  m.collectNear(0, 0, std::numeric_limits<double>::infinity(), all);
  EXPECT_EQ(all.size(), m.size());
  // Many cells in the box relative to the map: the traversal path gives the same set.
  LandmarkMap small(1.0);
  small.insert(makeLandmark(1, 0.5, 0.5));
  small.insert(makeLandmark(2, 50.5, 0.5));
  std::vector<LandmarkMap::Ref> s;
  small.collectNear(0, 0, 10.0, s);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].landmark->id, 1u);
}

TEST(slam_LandmarkMap, CopySharesThenSeparatesOnWrite) {
  LandmarkMap a(4.0);
  for (int i = 0; i < 64; ++i) a.insert(makeLandmark(i, 4.5 * (i % 8), 4.5 * (i / 8)));
  const std::uint64_t k0 = a.cellKeyOf(0.0, 0.0), k1 = a.cellKeyOf(9.0, 9.0);
  const LandmarkMap::Cell* c0 = a.cellStorage(k0);
  const LandmarkMap::Cell* c1 = a.cellStorage(k1);
  ASSERT_NE(c0, nullptr);
  const long uses_before = a.cellUseCount(k0);

  LandmarkMap b = a;  // a particle copy: one pointer
  EXPECT_EQ(a.rootNode(), b.rootNode());
  EXPECT_EQ(a.rootUseCount(), 2);  // a and b own the same tree
  EXPECT_EQ(b.cellStorage(k0), c0);
  EXPECT_EQ(a.cellUseCount(k0), uses_before);  // cells are shared through nodes, not re-owned

  // Write through b: only the edited cell and the path above it separate.
  LandmarkMap::Edit e;
  e.ref = refOf(b, 0);
  e.value = *e.ref.landmark;
  e.value.counter = 99;
  b.apply({e}, {});
  EXPECT_NE(a.rootNode(), b.rootNode());
  EXPECT_NE(b.cellStorage(k0), c0);
  EXPECT_EQ(a.cellStorage(k0), c0);  // a unchanged
  EXPECT_EQ(b.cellStorage(k1), c1);  // untouched cell still shared
  EXPECT_EQ(a.rootUseCount(), 1);    // b now owns its own root (path copy)
  EXPECT_EQ(a.cellUseCount(k0), 1);
  EXPECT_EQ(asMap(a).at(0).counter, 0);
  EXPECT_EQ(asMap(b).at(0).counter, 99);

  // Storage accounting: b adds only a few nodes and one cell to a.
  std::unordered_set<const void*> seen;
  std::size_t bytes_a = 0, bytes_ab = 0;
  a.accumulateStorage(seen, bytes_a);
  bytes_ab = bytes_a;
  b.accumulateStorage(seen, bytes_ab);
  EXPECT_LT(bytes_ab - bytes_a, bytes_a / 4);
  // A deep copy shares nothing.
  const LandmarkMap d = a.deepCopy();
  EXPECT_NE(d.rootNode(), a.rootNode());
  EXPECT_NE(d.cellStorage(k0), c0);
  std::unordered_set<const void*> seen2;
  std::size_t bytes_d = 0;
  a.accumulateStorage(seen2, bytes_d);
  const std::size_t only_a = bytes_d;
  d.accumulateStorage(seen2, bytes_d);
  EXPECT_EQ(bytes_d, 2 * only_a);
  EXPECT_EQ(asMap(d).size(), a.size());
}

TEST(slam_LandmarkMap, EraseAndMoveAcrossCells) {
  LandmarkMap m(4.0);
  m.insert(makeLandmark(1, 1.0, 1.0));
  m.insert(makeLandmark(2, 1.5, 1.0));
  m.insert(makeLandmark(3, 10.0, 1.0));
  LandmarkMap::Edit mv;
  mv.ref = refOf(m, 1);
  mv.value = *mv.ref.landmark;
  mv.value.p_LinW_m.x() = 20.0;  // to another (new) cell
  LandmarkMap::Edit er;
  er.ref = refOf(m, 2);
  er.erase = true;
  m.apply({mv, er}, {});
  EXPECT_EQ(m.size(), 2u);
  const auto got = asMap(m);
  EXPECT_EQ(got.count(2), 0u);
  EXPECT_DOUBLE_EQ(got.at(1).p_LinW_m.x(), 20.0);
  EXPECT_EQ(refOf(m, 1).cell_key, m.cellKeyOf(20.0, 1.0));
}

TEST(slam_LandmarkMap, DeterministicOrderAndBalancedDepth) {
  // Cells created in increasing key order (a robot driving in a line) must not degrade the tree.
  LandmarkMap m(1.0);
  for (int i = 0; i < 4096; ++i) m.insert(makeLandmark(i, i + 0.5, 0.5));
  const auto depth = [](const auto& self, const LandmarkMap::Node* n) -> int {
    return n ? 1 + std::max(self(self, n->left.get()), self(self, n->right.get())) : 0;
  };
  EXPECT_LT(depth(depth, m.rootNode()), 40);  // ~ 2-3 log2(4096) for a treap
  LandmarkMap m2(1.0);
  for (int i = 0; i < 4096; ++i) m2.insert(makeLandmark(i, i + 0.5, 0.5));
  const auto a = m.landmarks(), b = m2.landmarks();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].id, b[i].id);
}

}  // namespace
