// SPDX-License-Identifier: BSD-3-Clause
// Marching cubes: the triangles that separate a cube's inside corners from its outside ones, for
// each of the 256 sign patterns, derived once from the cube's geometry (no hand-written table).
#pragma once

#include <array>
#include <cstdint>

namespace raymap {

/// @brief Corner c (0..7) of a cube sits at offset (c & 1, (c >> 1) & 1, (c >> 2) & 1) from its
/// lowest corner, in grid steps.
inline constexpr int kCubeCorners = 8;
inline constexpr int kCubeEdges = 12;
/// More than any case needs: a case's triangles are its crossed edges (at most 12) less two per
/// surface loop (at least one), so at most 10.
inline constexpr int kMaxCubeTriangles = 10;

/// @brief An edge of the cube: from corner `lower` one step along `axis` (0 x, 1 y, 2 z).
struct CubeEdge {
  std::uint8_t lower = 0;
  std::uint8_t axis = 0;
  std::uint8_t upper() const noexcept { return static_cast<std::uint8_t>(lower | (1u << axis)); }
};

/// @brief The 12 edges, in the order the triangles of marchingCubesCase() index them.
const std::array<CubeEdge, kCubeEdges>& cubeEdges() noexcept;

/// @brief The surface inside a cube for one sign pattern.
struct CubeCase {
  std::uint8_t triangle_count = 0;
  /// Each triangle's vertices are the surface's crossings of these edges (indices into
  /// cubeEdges()), wound counter-clockwise seen from the outside: the right-hand normal points
  /// from the inside corners to the outside ones.
  std::array<std::array<std::uint8_t, 3>, kMaxCubeTriangles> triangles{};
};

/// @brief The triangles for `inside_mask` (bit c set: corner c is inside the surface).
///
/// How the table is made: on each face of the cube the surface's trace is a segment between the
/// two crossed edges, or, where the inside corners are diagonal (4 crossed edges; the ambiguous
/// face), two segments that each cut one inside corner off (inside corners are never joined
/// across a face). That rule depends only on the face's own corners, so two cubes that share a
/// face trace it alike and the surface of a grid of cubes is closed (a table that resolves the
/// ambiguous face one way in a cube and the other way in its neighbour leaves a crack between
/// them). Each segment is directed with the
/// inside on its left seen from outside the cube; the segments then chain into closed loops,
/// and each loop is triangulated as a fan.
/// Thread-safety: the table is built on first use (thread-safe static) and read-only after.
const CubeCase& marchingCubesCase(unsigned inside_mask) noexcept;

}  // namespace raymap
