// SPDX-License-Identifier: BSD-3-Clause
// The marching cubes cases, derived from the cube's faces (see marching_cubes.hpp).
#include "src/map/marching_cubes.hpp"

#include <utility>

#include "raymap/assert.hpp"

#include "src/core/vec3.hpp"

namespace raymap {
namespace {

Vec3d cornerPosition(unsigned corner) {
  return {static_cast<double>(corner & 1u), static_cast<double>((corner >> 1) & 1u),
          static_cast<double>((corner >> 2) & 1u)};
}

std::array<CubeEdge, kCubeEdges> makeEdges() {
  std::array<CubeEdge, kCubeEdges> edges{};
  std::size_t n = 0;
  for (unsigned axis = 0; axis < 3; ++axis) {
    for (unsigned corner = 0; corner < kCubeCorners; ++corner) {
      if ((corner & (1u << axis)) == 0u) {
        edges[n++] = CubeEdge{static_cast<std::uint8_t>(corner), static_cast<std::uint8_t>(axis)};
      }
    }
  }
  return edges;
}

/// Index in `edges` of the edge between two corners that differ in one bit.
int edgeBetween(const std::array<CubeEdge, kCubeEdges>& edges, unsigned a, unsigned b) {
  const unsigned lower = a < b ? a : b;
  const unsigned bit = a ^ b;
  for (int e = 0; e < kCubeEdges; ++e) {
    if (edges[static_cast<std::size_t>(e)].lower == lower &&
        (1u << edges[static_cast<std::size_t>(e)].axis) == bit) {
      return e;
    }
  }
  RAYMAP_ENSURES(false && "corners are not adjacent");
  return -1;
}

Vec3d edgeMidpoint(const CubeEdge& edge) {
  return (cornerPosition(edge.lower) + cornerPosition(edge.upper())) * 0.5;
}

/// True when edges a and b both lie on one face of the cube.
bool shareAFace(const CubeEdge& a, const CubeEdge& b) {
  for (unsigned axis = 0; axis < 3; ++axis) {
    const unsigned bit = 1u << axis;
    if (a.axis != axis && b.axis != axis && (a.lower & bit) == (b.lower & bit)) {
      return true;
    }
  }
  return false;
}

/// True when a fan from loop[apex] would have a diagonal (not a side of the loop) between two
/// edges on one face.
bool diagonalOnAFace(const std::array<CubeEdge, kCubeEdges>& edges,
                     const std::array<std::uint8_t, kCubeEdges>& loop, int length, int apex) {
  for (int i = 2; i + 1 < length; ++i) {
    const int other = (apex + i) % length;
    if (shareAFace(edges[loop[static_cast<std::size_t>(apex)]],
                   edges[loop[static_cast<std::size_t>(other)]])) {
      return true;
    }
  }
  return false;
}

/// next[e]: the crossed edge the surface's trace goes on to from edge e (a directed segment on
/// one face of the cube); -1 for edges the surface does not cross.
using EdgeLinks = std::array<int, kCubeEdges>;

/// Links the segment between two crossed edges of a face, directed so that the inside is on its
/// left seen from outside the face.
void addSegment(const std::array<CubeEdge, kCubeEdges>& edges, EdgeLinks& next, int from, int to,
                Vec3d face_normal, Vec3d inside_point) {
  const Vec3d a = edgeMidpoint(edges[static_cast<std::size_t>(from)]);
  const Vec3d b = edgeMidpoint(edges[static_cast<std::size_t>(to)]);
  // Seen from outside (along -face_normal), face_normal x direction points to the left.
  if (face_normal.cross(b - a).dot(inside_point - a) < 0.0) {
    std::swap(from, to);
  }
  RAYMAP_ENSURES(next[static_cast<std::size_t>(from)] == -1);
  next[static_cast<std::size_t>(from)] = to;
}

/// The surface's segments on the face of the cube normal to `axis` at `side` (0 or 1).
void traceFace(unsigned inside_mask, const std::array<CubeEdge, kCubeEdges>& edges, unsigned axis,
               unsigned side, EdgeLinks& next) {
  const auto inside = [&](unsigned corner) { return ((inside_mask >> corner) & 1u) != 0u; };
  const unsigned u = (axis + 1) % 3;
  const unsigned v = (axis + 2) % 3;
  // The face's corners in order round it; face edge k joins ring[k] and ring[k + 1].
  std::array<unsigned, 4> ring{};
  for (unsigned k = 0; k < 4; ++k) {
    const unsigned bu = (k == 1 || k == 2) ? 1u : 0u;
    const unsigned bv = k >= 2 ? 1u : 0u;
    ring[k] = (side << axis) | (bu << u) | (bv << v);
  }
  Vec3d normal{};
  normal[static_cast<int>(axis)] = side != 0u ? 1.0 : -1.0;
  const auto face_edge = [&](unsigned k) {
    return edgeBetween(edges, ring[k % 4], ring[(k + 1) % 4]);
  };
  std::array<unsigned, 4> crossed{};
  unsigned crossed_count = 0;
  Vec3d inside_sum{};
  unsigned inside_count = 0;
  for (unsigned k = 0; k < 4; ++k) {
    if (inside(ring[k]) != inside(ring[(k + 1) % 4])) {
      crossed[crossed_count++] = k;
    }
    if (inside(ring[k])) {
      inside_sum = inside_sum + cornerPosition(ring[k]);
      ++inside_count;
    }
  }
  if (crossed_count == 2) {
    addSegment(edges, next, face_edge(crossed[0]), face_edge(crossed[1]), normal,
               inside_sum * (1.0 / inside_count));
  } else if (crossed_count == 4) {
    // Inside corners diagonal: cut each off on its own (the two face edges at corner k are
    // k - 1 and k).
    for (unsigned k = 0; k < 4; ++k) {
      if (inside(ring[k])) {
        addSegment(edges, next, face_edge(k + 3), face_edge(k), normal, cornerPosition(ring[k]));
      }
    }
  }
}

/// The surface's trace round the cube's six faces.
EdgeLinks traceSurface(unsigned inside_mask, const std::array<CubeEdge, kCubeEdges>& edges) {
  EdgeLinks next{};
  next.fill(-1);
  for (unsigned axis = 0; axis < 3; ++axis) {
    for (unsigned side = 0; side < 2; ++side) {
      traceFace(inside_mask, edges, axis, side, next);
    }
  }
  return next;
}

/// Each closed loop of the trace as a fan of triangles.
CubeCase triangulateLoops(const std::array<CubeEdge, kCubeEdges>& edges, const EdgeLinks& next) {
  CubeCase result;
  std::array<bool, kCubeEdges> used{};
  for (int start = 0; start < kCubeEdges; ++start) {
    if (next[static_cast<std::size_t>(start)] < 0 || used[static_cast<std::size_t>(start)]) {
      continue;
    }
    std::array<std::uint8_t, kCubeEdges> loop{};
    int length = 0;
    for (int e = start; !used[static_cast<std::size_t>(e)]; e = next[static_cast<std::size_t>(e)]) {
      RAYMAP_ENSURES(e >= 0);
      used[static_cast<std::size_t>(e)] = true;
      loop[static_cast<std::size_t>(length++)] = static_cast<std::uint8_t>(e);
    }
    // The fan's apex: a vertex none of whose diagonals lies on a face of the cube. Such a
    // diagonal joins the two segments of an ambiguous face; the neighbouring cube would put the
    // same diagonal on that face, four triangles would meet at one edge and the surface would
    // pinch there.
    int apex = 0;
    while (apex < length && diagonalOnAFace(edges, loop, length, apex)) {
      ++apex;
    }
    RAYMAP_ENSURES(apex < length);
    const auto at = [&](int i) { return loop[static_cast<std::size_t>((apex + i) % length)]; };
    // The loop runs counter-clockwise round the inside seen from outside the cube, so its
    // right-hand normal points into the inside: the fan is wound the other way.
    for (int i = 1; i + 1 < length; ++i) {
      RAYMAP_ENSURES(result.triangle_count < kMaxCubeTriangles);
      result.triangles[result.triangle_count++] = {at(0), at(i + 1), at(i)};
    }
  }
  return result;
}

CubeCase makeCase(unsigned inside_mask, const std::array<CubeEdge, kCubeEdges>& edges) {
  return triangulateLoops(edges, traceSurface(inside_mask, edges));
}

struct CaseTable {
  std::array<CubeEdge, kCubeEdges> edges = makeEdges();
  std::array<CubeCase, 256> cases{};
  CaseTable() {
    for (unsigned mask = 0; mask < 256u; ++mask) {
      cases[mask] = makeCase(mask, edges);
    }
  }
};

const CaseTable& table() noexcept {
  static const CaseTable instance;
  return instance;
}

}  // namespace

const std::array<CubeEdge, kCubeEdges>& cubeEdges() noexcept { return table().edges; }

const CubeCase& marchingCubesCase(unsigned inside_mask) noexcept {
  RAYMAP_EXPECTS(inside_mask < 256u);
  return table().cases[inside_mask];
}

}  // namespace raymap
