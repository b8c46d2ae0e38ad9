// Union-find that also keeps, for every element, whether it is flipped relative to the root of
// its set: the relative signs along a spanning forest without building the forest.
#pragma once
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace pointscale {

class SignedUnionFind {
 public:
  // n elements (n < 2^31), each its own set, unflipped.
  explicit SignedUnionFind(std::size_t n) : link_(n), rank_(n, 0) {
    for (std::size_t i = 0; i < n; ++i) link_[i] = static_cast<std::uint32_t>(i);
  }

  struct Root {
    std::uint32_t root;
    std::uint32_t flip;  // 1 when x is flipped relative to root
  };

  // x's root and x's flip relative to it. Compresses the path: every element on it then
  // links straight to the root, with its own flip.
  Root find(std::uint32_t x) {
    std::uint32_t r = x, flip = 0;
    while (parent(r) != r) { flip ^= link_[r] >> 31; r = parent(r); }
    for (std::uint32_t y = x, f = flip; parent(y) != r && y != r;) {
      const std::uint32_t next = parent(y), own = link_[y] >> 31;
      link_[y] = r | (f << 31);
      f ^= own;
      y = next;
    }
    return {r, flip};
  }

  // Joins the sets of a and b so that b's flip relative to a is `flip` (0 or 1). Returns false,
  // and changes nothing, when they are in one set already.
  bool join(std::uint32_t a, std::uint32_t b, std::uint32_t flip) {
    const Root ra = find(a), rb = find(b);
    if (ra.root == rb.root) return false;
    // The root that goes under the other must flip so that a and b end up `flip` apart.
    const std::uint32_t f = ra.flip ^ rb.flip ^ flip;
    std::uint32_t top = ra.root, under = rb.root;
    if (rank_[top] < rank_[under]) std::swap(top, under);
    if (rank_[top] == rank_[under]) ++rank_[top];
    link_[under] = top | (f << 31);
    return true;
  }

 private:
  std::uint32_t parent(std::uint32_t x) const { return link_[x] & 0x7FFFFFFFu; }
  std::vector<std::uint32_t> link_;  // parent index, flip relative to the parent in the top bit
  std::vector<std::uint8_t> rank_;   // union by rank: at most log2(n) < 32
};

}  // namespace pointscale
