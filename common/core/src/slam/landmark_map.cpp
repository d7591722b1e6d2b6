// Persistent (path-copying) treap of grid cells holding landmarks; see landmark_map.h.
#include "omnislam/core/slam/landmark_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace omnislam::slam {

namespace {

using NodePtr = LandmarkMap::NodePtr;
using Node = LandmarkMap::Node;
using Cell = LandmarkMap::Cell;

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Heap order on (priority, key) so that equal priorities still give one shape.
bool above(std::uint64_t pa, std::uint64_t ka, const Node& b) {
  return pa > b.priority || (pa == b.priority && ka < b.key);
}

std::int32_t cellIndex(double v_m, double cell_m) {
  const double c = std::floor(v_m / cell_m);
  constexpr double lo = std::numeric_limits<std::int32_t>::min(), hi = std::numeric_limits<std::int32_t>::max();
  if (!(c >= lo)) return std::numeric_limits<std::int32_t>::min();  // also NaN
  if (c > hi) return std::numeric_limits<std::int32_t>::max();
  return static_cast<std::int32_t>(c);
}

// Order-preserving map of a signed cell index to unsigned.
std::uint64_t biased(std::int32_t v) { return static_cast<std::uint64_t>(static_cast<std::uint32_t>(v) ^ 0x80000000u); }
std::uint64_t makeKey(std::int32_t cx, std::int32_t cy) { return (biased(cx) << 32) | biased(cy); }
std::int32_t keyCy(std::uint64_t key) {
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(key & 0xFFFFFFFFull) ^ 0x80000000u);
}

std::pair<NodePtr, NodePtr> split(const NodePtr& t, std::uint64_t key) {  // (< key, > key)
  if (!t) return {nullptr, nullptr};
  auto n = std::make_shared<Node>(*t);
  if (t->key < key) {
    auto [l, r] = split(t->right, key);
    n->right = std::move(l);
    return {std::move(n), std::move(r)};
  }
  auto [l, r] = split(t->left, key);
  n->left = std::move(r);
  return {std::move(l), std::move(n)};
}

// Inserts a key that is not yet in the tree.
NodePtr insertNew(const NodePtr& t, std::uint64_t key, std::uint64_t prio, std::shared_ptr<const Cell> cell) {
  if (!t || above(prio, key, *t)) {
    auto n = std::make_shared<Node>();
    n->key = key;
    n->priority = prio;
    n->cell = std::move(cell);
    auto [l, r] = split(t, key);
    n->left = std::move(l);
    n->right = std::move(r);
    return n;
  }
  auto n = std::make_shared<Node>(*t);
  if (key < t->key) {
    n->left = insertNew(t->left, key, prio, std::move(cell));
  } else {
    n->right = insertNew(t->right, key, prio, std::move(cell));
  }
  return n;
}

using CellUpdate = std::pair<std::uint64_t, std::vector<Landmark>>;
using UpdIt = std::vector<CellUpdate>::iterator;

// Replaces the cells of existing keys in [b, e) (sorted by key), copying each node on the union of
// their paths once.
NodePtr replaceCells(const NodePtr& t, UpdIt b, UpdIt e) {
  if (b == e || !t) return t;
  const auto mid = std::lower_bound(b, e, t->key, [](const CellUpdate& u, std::uint64_t k) { return u.first < k; });
  auto n = std::make_shared<Node>(*t);
  auto after = mid;
  if (mid != e && mid->first == t->key) {
    auto c = std::make_shared<Cell>();
    c->landmarks = std::move(mid->second);
    n->cell = std::move(c);
    ++after;
  }
  n->left = replaceCells(t->left, b, mid);
  n->right = replaceCells(t->right, after, e);
  return n;
}

template <class F>
void inorder(const Node* t, F&& f) {
  if (!t) return;
  inorder(t->left.get(), f);
  f(*t);
  inorder(t->right.get(), f);
}

// In-order over keys in [lo, hi].
template <class F>
void inorderRange(const Node* t, std::uint64_t lo, std::uint64_t hi, F&& f) {
  if (!t) return;
  if (t->key > lo) inorderRange(t->left.get(), lo, hi, f);
  if (t->key >= lo && t->key <= hi) f(*t);
  if (t->key < hi) inorderRange(t->right.get(), lo, hi, f);
}

void appendCell(const Node& n, std::vector<LandmarkMap::Ref>& out) {
  if (!n.cell) return;
  const auto& v = n.cell->landmarks;
  for (std::size_t i = 0; i < v.size(); ++i) out.push_back({n.key, static_cast<std::uint32_t>(i), &v[i]});
}

NodePtr cloneTree(const NodePtr& t) {
  if (!t) return nullptr;
  auto n = std::make_shared<Node>();
  n->key = t->key;
  n->priority = t->priority;
  n->cell = t->cell ? std::make_shared<Cell>(*t->cell) : nullptr;
  n->left = cloneTree(t->left);
  n->right = cloneTree(t->right);
  return n;
}

}  // namespace

LandmarkMap::LandmarkMap(double cell_size_m) : cell_size_m_(cell_size_m > 0.0 ? cell_size_m : 4.0) {}

std::uint64_t LandmarkMap::cellKeyOf(double x_m, double y_m) const {
  return makeKey(cellIndex(x_m, cell_size_m_), cellIndex(y_m, cell_size_m_));
}

const Node* LandmarkMap::find(std::uint64_t key) const {
  const Node* t = root_.get();
  while (t && t->key != key) t = key < t->key ? t->left.get() : t->right.get();
  return t;
}

void LandmarkMap::collectAll(std::vector<Ref>& out) const {
  inorder(root_.get(), [&](const Node& n) { appendCell(n, out); });
}

void LandmarkMap::collectNear(double x_m, double y_m, double reach_m, std::vector<Ref>& out) const {
  if (!root_) return;
  if (!std::isfinite(reach_m)) {
    collectAll(out);
    return;
  }
  const std::int32_t cx0 = cellIndex(x_m - reach_m, cell_size_m_), cx1 = cellIndex(x_m + reach_m, cell_size_m_);
  const std::int32_t cy0 = cellIndex(y_m - reach_m, cell_size_m_), cy1 = cellIndex(y_m + reach_m, cell_size_m_);
  const double box_cells = (static_cast<double>(cx1) - cx0 + 1.0) * (static_cast<double>(cy1) - cy0 + 1.0);
  if (box_cells <= static_cast<double>(num_cells_)) {
    // A column's cells are consecutive keys (cx high, cy low): one range walk per column, in the
    // order cell-by-cell look-ups gave (cy increasing), without a look-up from the root per cell.
    for (std::int64_t cx = cx0; cx <= cx1; ++cx) {
      const auto x = static_cast<std::int32_t>(cx);
      inorderRange(root_.get(), makeKey(x, cy0), makeKey(x, cy1), [&](const Node& n) { appendCell(n, out); });
    }
    return;
  }
  inorderRange(root_.get(), makeKey(cx0, std::numeric_limits<std::int32_t>::min()),
               makeKey(cx1, std::numeric_limits<std::int32_t>::max()), [&](const Node& n) {
                 const std::int32_t cy = keyCy(n.key);
                 if (cy >= cy0 && cy <= cy1) appendCell(n, out);
               });
}

std::vector<Landmark> LandmarkMap::landmarks() const {
  std::vector<Ref> refs;
  collectAll(refs);
  std::vector<Landmark> out;
  out.reserve(refs.size());
  for (const auto& r : refs) out.push_back(*r.landmark);
  return out;
}

void LandmarkMap::apply(const std::vector<Edit>& edits, const std::vector<Landmark>& inserts) {
  if (edits.empty() && inserts.empty()) return;
  std::vector<CellUpdate> updates;  // kept sorted by key
  const auto slot = [&](std::uint64_t key) -> std::vector<Landmark>& {
    auto it = std::lower_bound(updates.begin(), updates.end(), key,
                               [](const CellUpdate& u, std::uint64_t k) { return u.first < k; });
    if (it == updates.end() || it->first != key) {
      std::vector<Landmark> start;
      if (const Node* n = find(key); n && n->cell) start = n->cell->landmarks;
      it = updates.insert(it, {key, std::move(start)});
    }
    return it->second;
  };
  std::vector<Landmark> moved;
  editCells(edits, updates, moved);
  const auto add = [&](const Landmark& lm) {
    slot(cellKeyOf(lm.p_LinW_m.x(), lm.p_LinW_m.y())).push_back(lm);
    ++size_;
  };
  for (const auto& lm : moved) add(lm);
  for (const auto& lm : inserts) add(lm);
  commitCells(updates);
}

void LandmarkMap::editCells(const std::vector<Edit>& edits, std::vector<CellUpdate>& updates,
                            std::vector<Landmark>& moved) {
  // Edits, grouped per cell.
  std::vector<const Edit*> order;
  order.reserve(edits.size());
  for (const auto& e : edits) order.push_back(&e);
  std::sort(order.begin(), order.end(), [](const Edit* a, const Edit* b) {
    return a->ref.cell_key != b->ref.cell_key ? a->ref.cell_key < b->ref.cell_key : a->ref.index < b->ref.index;
  });
  for (std::size_t i = 0; i < order.size();) {
    const std::uint64_t key = order[i]->ref.cell_key;
    const Node* n = find(key);
    const std::vector<Landmark>* old = (n && n->cell) ? &n->cell->landmarks : nullptr;
    std::vector<Landmark> fresh;
    fresh.reserve(old ? old->size() : 0);
    std::size_t j = i;
    for (std::size_t idx = 0; old && idx < old->size(); ++idx) {
      while (j < order.size() && order[j]->ref.cell_key == key && order[j]->ref.index < idx) ++j;  // stale
      if (j < order.size() && order[j]->ref.cell_key == key && order[j]->ref.index == idx) {
        const Edit& e = *order[j];
        --size_;
        if (!e.erase) {
          if (cellKeyOf(e.value.p_LinW_m.x(), e.value.p_LinW_m.y()) == key) {
            fresh.push_back(e.value);
            ++size_;
          } else {
            moved.push_back(e.value);
          }
        }
        ++j;
      } else {
        fresh.push_back((*old)[idx]);
      }
    }
    while (j < order.size() && order[j]->ref.cell_key == key) ++j;
    if (old) updates.emplace_back(key, std::move(fresh));  // keys arrive in increasing order
    i = j;
  }
}

void LandmarkMap::commitCells(std::vector<CellUpdate>& updates) {
  std::vector<CellUpdate> existing, created;
  for (auto& u : updates) (find(u.first) ? existing : created).push_back(std::move(u));
  root_ = replaceCells(root_, existing.begin(), existing.end());
  for (auto& u : created) {
    auto c = std::make_shared<Cell>();
    c->landmarks = std::move(u.second);
    root_ = insertNew(root_, u.first, splitmix64(u.first), std::move(c));
    ++num_cells_;
  }
}

LandmarkMap LandmarkMap::deepCopy() const {
  LandmarkMap m(cell_size_m_);
  m.root_ = cloneTree(root_);
  m.size_ = size_;
  m.num_cells_ = num_cells_;
  return m;
}

const LandmarkMap::Cell* LandmarkMap::cellStorage(std::uint64_t key) const {
  const Node* n = find(key);
  return n ? n->cell.get() : nullptr;
}

long LandmarkMap::cellUseCount(std::uint64_t key) const {
  const Node* n = find(key);
  return n ? n->cell.use_count() : 0;
}

void LandmarkMap::accumulateStorage(std::unordered_set<const void*>& seen, std::size_t& bytes) const {
  // make_shared puts a control block (two counters and a vtable pointer) beside each object.
  constexpr std::size_t kControl = 16;
  const auto walk = [&](const auto& self, const Node* t) -> void {
    if (!t || !seen.insert(t).second) return;  // a shared subtree was counted with its first owner
    bytes += sizeof(Node) + kControl;
    if (t->cell && seen.insert(t->cell.get()).second) {
      bytes += sizeof(Cell) + kControl + t->cell->landmarks.capacity() * sizeof(Landmark);
    }
    self(self, t->left.get());
    self(self, t->right.get());
  };
  walk(walk, root_.get());
}

std::vector<std::pair<std::uint64_t, std::shared_ptr<const Cell>>> LandmarkMap::cells() const {
  std::vector<std::pair<std::uint64_t, std::shared_ptr<const Cell>>> out;
  out.reserve(num_cells_);
  inorder(root_.get(), [&](const Node& n) { out.emplace_back(n.key, n.cell); });
  return out;
}

LandmarkMap LandmarkMap::fromCells(double cell_size_m,
                                   const std::vector<std::pair<std::uint64_t, std::shared_ptr<const Cell>>>& cells) {
  LandmarkMap m(cell_size_m);
  if (m.cell_size_m_ != cell_size_m) throw std::invalid_argument("landmark map: cell size must be > 0");
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const auto& [key, cell] = cells[i];
    if (!cell) throw std::invalid_argument("landmark map: cell " + std::to_string(i) + " is empty storage");
    if (i > 0 && key <= cells[i - 1].first)
      throw std::invalid_argument("landmark map: cell keys not strictly increasing at cell " + std::to_string(i));
    for (const Landmark& l : cell->landmarks)
      if (m.cellKeyOf(l.p_LinW_m.x(), l.p_LinW_m.y()) != key)
        throw std::invalid_argument("landmark map: landmark " + std::to_string(l.id) + " lies outside its cell");
    // The shape depends only on the key set (priority = hash(key)): the same tree as the one saved.
    m.root_ = insertNew(m.root_, key, splitmix64(key), cell);
    m.size_ += cell->landmarks.size();
    ++m.num_cells_;
  }
  return m;
}

}  // namespace omnislam::slam
