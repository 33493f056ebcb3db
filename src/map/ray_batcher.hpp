// SPDX-License-Identifier: BSD-3-Clause
// The one batching loop: prepare rays into a batch, integrate it when full and at the scan
// boundary (per-scan semantics). raymap::Mapper, `raymap populate` and raymapd's integrator all
// integrate through it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "raymap/error.hpp"
#include "raymap/expected.hpp"

#include "platform/page_array.hpp"
#include "src/map/backend.hpp"
#include "src/map/ray.hpp"
#include "src/map/ray_preparer.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap {

/// @brief What a RayBatcher did so far. Plain counters (not synchronised).
struct BatcherCounters {
  std::uint64_t batches = 0;          ///< backend integrate() calls
  std::uint64_t rays_integrated = 0;  ///< prepared rays (ray pieces) in batches that went in
  std::uint64_t batches_failed = 0;   ///< integrate() calls that returned an error (rays lost)
  std::uint64_t scans = 0;            ///< distinct scans (runs of one Ray::scan) seen
  std::uint64_t scans_split = 0;      ///< per-scan: scans larger than a batch, integrated in parts
  std::uint64_t parallel_prepares = 0;  ///< runs of rays prepared on the backend's host threads
  std::uint64_t device_batches = 0;     ///< of batches: rays prepared on the device
  std::uint64_t points_deskewed_on_device = 0;  ///< integratePoints(): points the device deskewed
  /// Rays left out because their pieces (RayFilter::segment_length_m) do not fit even an empty
  /// batch (a batch smaller than RayFilter::kMaxPiecesPerRay): each is skipped and counted, the
  /// rays after it still go in.
  std::uint64_t rays_too_many_pieces = 0;
};

/// @brief Prepares rays (RayPreparer) into a fixed batch and hands full batches to a backend.
///
/// Batches are integrated when full, by flush(), and, under per-scan semantics (each voxel at
/// most once per scan), whenever a ray of another scan (Ray::scan) arrives: a batch never mixes
/// two scans there. A scan larger than the batch is integrated in parts (counted: scans_split),
/// each part with per-scan semantics. Prepared rays of different preparers (sensors with other
/// range limits) may share a batch.
///
/// A failed backend call loses that batch's rays (counted: batches_failed); later rays still go
/// in, and the call that saw the failure returns the first error it met.
///
/// With a backend that has several host threads (the CPU backend on N threads), a long enough run
/// of rays is prepared on those threads, each a contiguous range, and the ranges are joined in
/// order: the batch is the one a single thread prepares (not with segmented rays, whose piece
/// counts are not known in advance: those are prepared on the calling thread).
///
/// With a backend that prepares rays on the device (Backend::preparesOnDevice), the batch holds
/// the rays as they came (world frame) and the backend prepares them: the same maps and the same
/// counters, which reach the preparer when the batch is integrated (flush(), a full batch, a scan's
/// end). A scan that per-scan semantics would integrate in parts goes the host's way instead,
/// so the parts are the ones the host makes. A rolling map whose window moves while rays wait in
/// the batch is the exception: those rays go in after the move either way, but which of them
/// went in before it depends on when batches fill, counted in prepared rays on the host and in
/// rays as they came here. flush() before moving the window (raymapd moves it only with the
/// batch empty) and the maps are the same.
///
/// Thread-safety: one thread. @rt add(), flush(): allocate no memory and throw nothing (the batch
/// is allocated by the constructor); they block only in the backend.
class RayBatcher {
 public:
  /// @param batch_rays capacity of the batch in prepared rays (at least 1).
  /// @pre `backend` integrates `map` and outlives the batcher.
  RayBatcher(const VoxelMap& map, Backend& backend, std::size_t batch_rays);

  /// @brief Prepares `rays` with `preparer` into the batch, integrating full batches (and, per
  /// scan, each finished scan) as it goes. Every ray is consumed.
  Expected<void, IntegrateError> add(RayPreparer& preparer, std::span<const Ray> rays) noexcept;
  /// @brief Integrates what the batch holds. Does not wait for a device (Backend::synchronise()).
  Expected<void, IntegrateError> flush() noexcept;
  /// @brief add() of the rays deskewedRay() makes of `points` with `tables`, then flush(): with
  /// a backend that deskews on the device (Backend::deskewsOnDevice) the points go to it as they
  /// are, else the host deskews them here (kernels/common/deskew.h either way). The same maps and
  /// counters as add() of the host's rays and flush().
  Expected<void, IntegrateError> integratePoints(RayPreparer& preparer,
                                                 std::span<const rm_scan_point> points,
                                                 const DeskewTables& tables) noexcept;

  /// @brief The room of a caller that gathers its batch itself, capacity() world rays long:
  /// raymapd's integrator converts scans into it without the map lock and integrates it in
  /// slices under the lock (integrateStaged()), so the rays are batched once, here. The first
  /// call allocates and touches the whole room (start-up: no page faults later); later calls
  /// return the same room. Not thread-safe.
  std::span<Ray> staging();
  /// @brief Integrates staged rays [first, first + count) now: what add() of them and flush()
  /// do, the same maps and counters, except that rays the backend prepares on the device go to
  /// it from the staging room in place, not copied into the batch first.
  /// @pre staging() was called; first + count <= capacity().
  Expected<void, IntegrateError> integrateStaged(RayPreparer& preparer, std::size_t first,
                                                 std::size_t count) noexcept;

  /// @brief Forgets the scan the last rays belonged to: the next rays start a new scan even when
  /// they carry the same Ray::scan (a stream read again from its start with the same batcher).
  /// Call after flush().
  void endStream() noexcept {
    have_scan_ = false;
    scan_split_ = false;
    scan_on_host_ = false;
  }
  /// Rays waiting in the batch (prepared, or as they came for the device to prepare).
  std::size_t pending() const noexcept { return fill_ + raw_fill_; }
  std::size_t capacity() const noexcept { return capacity_; }
  const BatcherCounters& counters() const noexcept { return counters_; }
  Backend& backend() noexcept { return *backend_; }

 private:
  Backend* backend_;
  bool per_scan_;
  /// Page-backed, never initialised: a prepared ray is written before it is read, and a batch
  /// larger than the input (a 262,144-ray per-scan batch for one 8,000-ray scan) makes only the
  /// pages it fills resident.
  platform::PageArray<PreparedRay> batch_;
  std::size_t capacity_;
  std::size_t fill_ = 0;
  bool have_scan_ = false;
  bool scan_split_ = false;  // the current scan already went in in parts
  std::uint64_t scan_ = 0;   // Ray::scan of the rays in the batch
  BatcherCounters counters_;

  /// What one host thread's range gave (on a cache line of its own).
  struct alignas(64) PartResult {
    RayCounters counters;
    std::size_t written = 0;
  };
  /// Prepares all of `in` into the batch after its `fill_` rays on the backend's host threads;
  /// the caller makes sure every ray fits (no segmentation, room for in.size()).
  RayPreparer::Progress prepareOnHostThreads(RayPreparer& preparer,
                                             std::span<const Ray> in) noexcept;
  std::vector<PartResult> parts_;  // one per host thread of the backend

  /// Prepares `rays` (one scan's) into the batch on the host, integrating full batches.
  void addPrepared(RayPreparer& preparer, std::span<const Ray> rays,
                   Expected<void, IntegrateError>& first_error) noexcept;
  /// Adds `rays` (one scan's) for the device to prepare (Backend::integrateRays).
  void addForDevice(RayPreparer& preparer, std::span<const Ray> rays,
                    Expected<void, IntegrateError>& first_error) noexcept;
  /// Integrates `rays` through Backend::integrateRays, prepared with `params`, counting into
  /// `preparer`.
  Expected<void, IntegrateError> integrateOnDevice(RayPreparer& preparer,
                                                   const rm_prepare_params& params,
                                                   std::span<const Ray> rays) noexcept;
  /// Integrates the rays waiting for the device's preparation.
  Expected<void, IntegrateError> flushRaw() noexcept;

  // ---- preparation on the device ----
  platform::PageArray<Ray> raw_;  // rays waiting for the device to prepare them
  std::size_t raw_fill_ = 0;
  /// integrateStaged(): the rays waiting for the device are a view of the staging room (from
  /// raw_view_, raw_fill_ long), not copies in raw_.
  bool in_place_ = false;
  const Ray* raw_view_ = nullptr;
  /// The rays waiting for the device: raw_'s, or the staging room's in place.
  const Ray* rawData() const noexcept { return in_place_ ? raw_view_ : raw_.data(); }
  RayPreparer* raw_preparer_ = nullptr;  // the preparer of the rays in raw_
  rm_prepare_params raw_params_{};       // and its parameters when the first of them came
  bool scan_on_host_ = false;            // per-scan: this scan outgrew the batch, host prepares
  platform::PageArray<Ray> deskewed_;    // integratePoints(): points the host deskews

  // ---- a caller's own batch (staging(), integrateStaged()) ----
  std::vector<Ray> staged_;  // world rays, all touched at start-up
};

/// @brief The error a failed batch means for whoever integrates: a full store is kCapacity ("the
/// map needs more than the N regions (G GiB) its memory budget allows; raise <raise>", where
/// `raise` names the caller's setting), anything else kIo naming the backend. Allocates (not for
/// the real-time path).
Error integrateFailure(const VoxelMap& map, const Backend& backend, IntegrateError error,
                       std::string_view raise);

}  // namespace raymap
