// Copy-on-write landmark map of one particle: a persistent treap (tree of shared_ptr<const Node>)
// keyed by a 2D grid cell, each node holding its cell's landmarks. Copying a map copies one
// pointer; an edit copies only the edited cells and the O(log cells) nodes above them, so
// resampling never deep-copies maps and particles share every untouched part (docs/design/slam-core.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <unordered_set>
#include <utility>
#include <vector>

#include "omnislam/core/slam/types.h"

namespace omnislam::slam {

class LandmarkMap {
 public:
  /// Landmarks whose mean lies in one grid cell (order = insertion order, deterministic).
  struct Cell {
    std::vector<Landmark> landmarks;
  };
  /// Immutable tree node; priority = hash(key), so the tree shape depends only on the key set.
  struct Node {
    std::uint64_t key = 0;
    std::uint64_t priority = 0;
    std::shared_ptr<const Cell> cell;
    std::shared_ptr<const Node> left, right;
  };
  using NodePtr = std::shared_ptr<const Node>;

  /// A landmark as found in this map; `landmark` stays valid until the next apply()/insert().
  struct Ref {
    std::uint64_t cell_key = 0;
    std::uint32_t index = 0;
    const Landmark* landmark = nullptr;
  };
  /// Replace the referenced landmark by `value` (moved to another cell if its mean left the cell),
  /// or erase it.
  struct Edit {
    Ref ref;
    bool erase = false;
    Landmark value;
  };

  /// cell_size_m: side of the square grid cells in the x-y plane of W [m], > 0.
  explicit LandmarkMap(double cell_size_m = 4.0);

  double cellSize_m() const { return cell_size_m_; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  std::size_t numCells() const { return num_cells_; }
  std::uint64_t cellKeyOf(double x_m, double y_m) const;

  /// Appends every landmark, in key order then insertion order.
  void collectAll(std::vector<Ref>& out) const;
  /// Appends the landmarks of every cell meeting the square |x - x_m| <= reach_m, |y - y_m| <= reach_m
  /// (a superset of those within reach_m; reach_m = +infinity gives all). Deterministic order.
  void collectNear(double x_m, double y_m, double reach_m, std::vector<Ref>& out) const;
  /// Copies of all landmarks (collectAll order).
  std::vector<Landmark> landmarks() const;

  /// Applies edits (each ref from this map, at most one edit per landmark) and insertions, copying
  /// only the cells touched and the path to them.
  void apply(const std::vector<Edit>& edits, const std::vector<Landmark>& inserts);
  void insert(const Landmark& landmark) { apply({}, {landmark}); }

  /// Every cell in key order with its (shared) storage, for checkpoints.
  std::vector<std::pair<std::uint64_t, std::shared_ptr<const Cell>>> cells() const;
  /// The map holding these cells (as cells() gave them; the storage is shared, not copied), so that a
  /// restored map iterates in the same order as the one saved. Throws std::invalid_argument when the
  /// keys are not strictly increasing, a cell is null, or a landmark lies outside its cell.
  static LandmarkMap fromCells(double cell_size_m,
                               const std::vector<std::pair<std::uint64_t, std::shared_ptr<const Cell>>>& cells);

  /// A map with freshly allocated nodes and cells (nothing shared): the deep-copy baseline.
  LandmarkMap deepCopy() const;

  /// Storage identity, for tests and statistics.
  const Node* rootNode() const { return root_.get(); }
  long rootUseCount() const { return root_.use_count(); }  ///< maps sharing this root
  const Cell* cellStorage(std::uint64_t key) const;
  long cellUseCount(std::uint64_t key) const;  ///< owners of a cell's storage, 0 when absent
  /// Adds the bytes of nodes and cells not yet in `seen` (a shared subtree is counted once).
  void accumulateStorage(std::unordered_set<const void*>& seen, std::size_t& bytes) const;

 private:
  using CellLandmarks = std::pair<std::uint64_t, std::vector<Landmark>>;  ///< a cell's key and its new landmarks
  const Node* find(std::uint64_t key) const;
  /// apply()'s edits: each edited cell's new landmarks, in increasing key order, into `updates`; the
  /// edited landmarks that left their cell into `moved`.
  void editCells(const std::vector<Edit>& edits, std::vector<CellLandmarks>& updates, std::vector<Landmark>& moved);
  /// apply()'s end: the cells of `updates` into the tree, existing ones in one path-copying pass, then
  /// the new ones one by one.
  void commitCells(std::vector<CellLandmarks>& updates);
  double cell_size_m_;
  NodePtr root_;
  std::size_t size_ = 0;
  std::size_t num_cells_ = 0;
};

}  // namespace omnislam::slam
