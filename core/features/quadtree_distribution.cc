#include "core/features/quadtree_distribution.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace cblox {
namespace {

// A node: its rectangle [x0, x1) x [y0, y1) and its corners, idx[begin, end).
struct Node {
  int x0, x1, y0, y1;
  int begin, end;
  int size() const { return end - begin; }
  // More than one corner, and room to separate them (a 1 x 1 node only holds corners at the
  // same pixel).
  bool splittable() const { return size() > 1 && (x1 - x0 > 1 || y1 - y0 > 1); }
};

class Quadtree {
 public:
  explicit Quadtree(const std::vector<LevelCorner>& corners)
      : corners_(corners), idx_(corners.size()), tmp_(corners.size()) {
    std::iota(idx_.begin(), idx_.end(), 0);
  }

  std::vector<int>& idx() { return idx_; }

  // Appends the non-empty quadrants of `n` to *out (corner order kept within each quadrant).
  void split(const Node& n, std::vector<Node>* out) {
    const int hx = (n.x1 - n.x0 + 1) / 2;  // ceil of half the width
    const int hy = (n.y1 - n.y0 + 1) / 2;
    const int mx = n.x0 + hx, my = n.y0 + hy;
    int count[4] = {0, 0, 0, 0};
    const auto quadrant = [&](int i) {
      const LevelCorner& c = corners_[static_cast<size_t>(i)];
      return (c.x < mx ? 0 : 1) + (c.y < my ? 0 : 2);
    };
    for (int k = n.begin; k < n.end; ++k) ++count[quadrant(idx_[static_cast<size_t>(k)])];
    int pos[4];
    pos[0] = n.begin;
    for (int q = 1; q < 4; ++q) pos[q] = pos[q - 1] + count[q - 1];
    const int first[4] = {pos[0], pos[1], pos[2], pos[3]};
    for (int k = n.begin; k < n.end; ++k) {
      const int i = idx_[static_cast<size_t>(k)];
      tmp_[static_cast<size_t>(pos[quadrant(i)]++)] = i;
    }
    std::copy(tmp_.begin() + n.begin, tmp_.begin() + n.end, idx_.begin() + n.begin);
    const int xs[3] = {n.x0, mx, n.x1}, ys[3] = {n.y0, my, n.y1};
    for (int q = 0; q < 4; ++q) {
      if (count[q] == 0) continue;
      const int qx = q & 1, qy = q >> 1;
      out->push_back({xs[qx], xs[qx + 1], ys[qy], ys[qy + 1], first[q], first[q] + count[q]});
    }
  }

  int best(const Node& n) const {
    int best = idx_[static_cast<size_t>(n.begin)];
    for (int k = n.begin + 1; k < n.end; ++k) {
      const int i = idx_[static_cast<size_t>(k)];
      if (corners_[static_cast<size_t>(i)].response >
          corners_[static_cast<size_t>(best)].response) {
        best = i;
      }
    }
    return best;
  }

 private:
  const std::vector<LevelCorner>& corners_;
  std::vector<int> idx_, tmp_;
};

}  // namespace

std::vector<int> distributeQuadtree(const std::vector<LevelCorner>& corners, int min_x, int max_x,
                                    int min_y, int max_y, int wanted) {
  std::vector<int> result;
  if (wanted <= 0 || corners.empty() || max_x <= min_x || max_y <= min_y) return result;
  Quadtree tree(corners);
  std::vector<int>& idx = tree.idx();

  // Initial nodes side by side, as many as the aspect ratio.
  const int width = max_x - min_x, height = max_y - min_y;
  const int n_ini = std::max(
      1, static_cast<int>(std::round(static_cast<float>(width) / static_cast<float>(height))));
  const float hx = static_cast<float>(width) / static_cast<float>(n_ini);
  std::vector<int> bound(static_cast<size_t>(n_ini) + 1);
  for (int i = 0; i <= n_ini; ++i) {
    bound[static_cast<size_t>(i)] = min_x + static_cast<int>(hx * static_cast<float>(i));
  }
  bound.back() = max_x;
  // Corners outside the area are ignored (node -1).
  std::vector<int> node_of(corners.size(), -1);
  std::vector<int> count(static_cast<size_t>(n_ini), 0);
  for (size_t i = 0; i < corners.size(); ++i) {
    const LevelCorner& c = corners[i];
    if (c.x < min_x || c.x >= max_x || c.y < min_y || c.y >= max_y) continue;
    const auto it = std::upper_bound(bound.begin() + 1, bound.end() - 1, c.x);
    node_of[i] = static_cast<int>(it - bound.begin()) - 1;
    ++count[static_cast<size_t>(node_of[i])];
  }
  std::vector<Node> leaves;
  {
    std::vector<int> pos(static_cast<size_t>(n_ini) + 1, 0);
    for (size_t i = 0; i < count.size(); ++i) pos[i + 1] = pos[i] + count[i];
    std::vector<int> fill(pos.begin(), pos.end() - 1);
    for (size_t i = 0; i < corners.size(); ++i) {
      if (node_of[i] < 0) continue;
      idx[static_cast<size_t>(fill[static_cast<size_t>(node_of[i])]++)] = static_cast<int>(i);
    }
    for (int i = 0; i < n_ini; ++i) {
      if (count[static_cast<size_t>(i)] == 0) continue;
      leaves.push_back({bound[static_cast<size_t>(i)], bound[static_cast<size_t>(i) + 1], min_y,
                        max_y, pos[static_cast<size_t>(i)], pos[static_cast<size_t>(i) + 1]});
    }
  }

  const auto n_wanted = static_cast<size_t>(wanted);
  const auto expandable = [&] {
    size_t n = 0;
    for (const Node& node : leaves) n += node.splittable();
    return n;
  };
  std::vector<Node> next;
  while (leaves.size() < n_wanted) {
    const size_t to_expand = expandable();
    if (to_expand == 0) break;  // every node holds one corner
    if (leaves.size() + 3 * to_expand <= n_wanted) {
      // Splitting every node cannot pass `wanted`: split them all.
      next.clear();
      for (const Node& n : leaves) {
        if (!n.splittable()) {
          next.push_back(n);
        } else {
          tree.split(n, &next);
        }
      }
      leaves.swap(next);
      continue;
    }
    // Split the largest nodes first, one at a time, until there are `wanted` nodes.
    while (leaves.size() < n_wanted && expandable() > 0) {
      std::vector<size_t> order;
      for (size_t i = 0; i < leaves.size(); ++i) {
        if (leaves[i].splittable()) order.push_back(i);
      }
      std::stable_sort(order.begin(), order.end(),
                       [&](size_t a, size_t b) { return leaves[a].size() > leaves[b].size(); });
      std::vector<char> removed(leaves.size(), 0);
      size_t live = leaves.size();
      for (const size_t i : order) {
        const Node n = leaves[i];
        const size_t first_child = leaves.size();
        tree.split(n, &leaves);
        removed[i] = 1;
        live += leaves.size() - first_child - 1;
        if (live >= n_wanted) {
          // The last split may overshoot by up to 3 nodes (ORB-SLAM2 keeps them): drop the
          // children of that split whose best corner is weakest.
          std::vector<size_t> children;
          for (size_t c = first_child; c < leaves.size(); ++c) children.push_back(c);
          std::stable_sort(children.begin(), children.end(), [&](size_t a, size_t b) {
            return corners[static_cast<size_t>(tree.best(leaves[a]))].response <
                   corners[static_cast<size_t>(tree.best(leaves[b]))].response;
          });
          removed.resize(leaves.size(), 0);
          for (size_t k = 0; k < live - n_wanted; ++k) removed[children[k]] = 1;
          break;
        }
      }
      removed.resize(leaves.size(), 0);
      next.clear();
      for (size_t i = 0; i < leaves.size(); ++i) {
        if (!removed[i]) next.push_back(leaves[i]);
      }
      leaves.swap(next);
    }
    break;
  }

  result.reserve(leaves.size());
  for (const Node& n : leaves) result.push_back(tree.best(n));
  if (result.size() > n_wanted) {
    // More initial nodes than wanted: keep the strongest, in node order.
    std::vector<size_t> by_response(result.size());
    std::iota(by_response.begin(), by_response.end(), size_t{0});
    std::stable_sort(by_response.begin(), by_response.end(), [&](size_t a, size_t b) {
      return corners[static_cast<size_t>(result[a])].response >
             corners[static_cast<size_t>(result[b])].response;
    });
    std::vector<char> keep(result.size(), 0);
    for (size_t k = 0; k < n_wanted; ++k) keep[by_response[k]] = 1;
    size_t out = 0;
    for (size_t k = 0; k < result.size(); ++k) {
      if (keep[k]) result[out++] = result[k];
    }
    result.resize(out);
  }
  return result;
}

}  // namespace cblox
