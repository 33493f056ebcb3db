// SPDX-License-Identifier: BSD-3-Clause
// Trajectory: text parsing with line-numbered errors, pose interpolation, and writing.
#include "src/io/trajectory.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string_view>
#include <utility>

#include "src/io/atomic_file.hpp"
#include "src/io/byte_reader.hpp"

namespace raymap::io {
namespace {

constexpr std::size_t kPositionColumns = 4;     // time x y z
constexpr std::size_t kOrientationColumns = 8;  // time x y z qw qx qy qz
// Quaternions shorter than this are not rotations (a zero or garbage line), not just unnormalised.
constexpr double kMinQuaternionNorm = 1e-6;

bool isSeparator(char c) noexcept {
  return c == ' ' || c == '\t' || c == ',' || c == '\r' || c == '\v' || c == '\f';
}

/// Splits a line into at most `capacity` + 1 fields; returns how many were found.
std::size_t splitFields(std::string_view line, std::string_view* fields, std::size_t capacity) {
  std::size_t n = 0;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && isSeparator(line[i])) {
      ++i;
    }
    if (i == line.size()) {
      break;
    }
    const std::size_t start = i;
    while (i < line.size() && !isSeparator(line[i])) {
      ++i;
    }
    if (n < capacity) {
      fields[n] = line.substr(start, i - start);
    }
    ++n;
  }
  return n;
}

bool parseNumber(std::string_view text, double& value) noexcept {
  if (!text.empty() && text.front() == '+') {
    text.remove_prefix(1);
  }
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(text.data(), end, value);
  return !text.empty() && error == std::errc() && stop == end;
}

}  // namespace

Trajectory::Trajectory(std::string path, std::vector<TrajectorySample> samples,
                       bool has_orientation) noexcept
    : path_(std::move(path)), samples_(std::move(samples)), has_orientation_(has_orientation) {}

Result<Trajectory> Trajectory::fromSamples(std::vector<TrajectorySample> samples,
                                           bool has_orientation, std::string name) {
  if (samples.empty()) {
    return fail(ErrorCode::kFormat, name + ": the trajectory has no samples");
  }
  for (std::size_t i = 0; i < samples.size(); ++i) {
    TrajectorySample& sample = samples[i];
    const std::string where = name + ": sample " + std::to_string(i + 1) + ": ";
    if (!std::isfinite(sample.time_s) || !sample.position.allFinite()) {
      return fail(ErrorCode::kFormat, where + "time and position must be finite numbers");
    }
    if (i > 0 && !(sample.time_s > samples[i - 1].time_s)) {
      return fail(ErrorCode::kFormat, where + "times must increase strictly");
    }
    if (!has_orientation) {
      sample.orientation = Eigen::Quaterniond::Identity();
      continue;
    }
    const double norm = sample.orientation.norm();
    if (!std::isfinite(norm) || norm < kMinQuaternionNorm) {
      return fail(ErrorCode::kFormat, where + "the orientation quaternion is not a rotation");
    }
    sample.orientation.coeffs() /= norm;  // = normalized(), without a second norm
  }
  return Trajectory(std::move(name), std::move(samples), has_orientation);
}

namespace {

/// One sample line's values as a sample (`n`: 4 or 8 values), checked: finite, after the
/// previous sample's time (`time_text` as the file spells it), a quaternion that is a rotation.
Result<TrajectorySample> makeSample(const double* values, std::size_t n,
                                    const std::vector<TrajectorySample>& samples,
                                    const std::string& line_prefix, std::string_view time_text) {
  TrajectorySample sample;
  sample.time_s = values[0];
  sample.position = {values[1], values[2], values[3]};
  if (n == kOrientationColumns) {
    sample.orientation = Eigen::Quaterniond(values[4], values[5], values[6], values[7]);  // w x y z
  }
  if (!std::isfinite(sample.time_s) || !sample.position.allFinite()) {
    return fail(ErrorCode::kFormat, line_prefix + "time and position must be finite numbers");
  }
  if (!samples.empty() && !(sample.time_s > samples.back().time_s)) {
    return fail(ErrorCode::kFormat, line_prefix + "time " + std::string(time_text) +
                                        " does not come after the previous sample's time "
                                        "(times must increase strictly)");
  }
  if (n == kOrientationColumns) {
    const double norm = sample.orientation.norm();
    if (!std::isfinite(norm) || norm < kMinQuaternionNorm) {
      return fail(ErrorCode::kFormat,
                  line_prefix + "the quaternion (qw qx qy qz) is not a rotation");
    }
  }
  return sample;
}

}  // namespace

Result<Trajectory> Trajectory::load(const std::string& path) {
  // Trajectories are small next to the clouds; a modest buffer is plenty.
  auto reader = ByteReader::open(path, std::size_t{64} << 10);
  if (!reader) {
    return Unexpected(std::move(reader).error());
  }
  std::vector<TrajectorySample> samples;
  std::size_t columns = 0;  // of the first sample line; every line must match it
  bool may_be_header = true;
  for (;;) {
    std::string_view line;
    auto got = reader->readLine(line);
    if (!got) {
      return Unexpected(std::move(got).error());
    }
    if (!*got) {
      break;
    }
    const std::string line_prefix = path + ": line " + std::to_string(reader->lineNumber()) + ": ";
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) {
      line = line.substr(0, hash);
    }
    std::string_view fields[kOrientationColumns];
    const std::size_t n = splitFields(line, fields, kOrientationColumns);
    if (n == 0) {
      continue;
    }
    double values[kOrientationColumns] = {};
    std::size_t bad_field = n;
    for (std::size_t i = 0; i < std::min(n, kOrientationColumns); ++i) {
      if (!parseNumber(fields[i], values[i])) {
        bad_field = i;
        break;
      }
    }
    if (bad_field < n) {
      if (may_be_header) {
        may_be_header = false;  // a column-name line such as "time x y z qw qx qy qz"
        continue;
      }
      return fail(ErrorCode::kFormat,
                  line_prefix + "'" + std::string(fields[bad_field]) + "' is not a number");
    }
    may_be_header = false;
    if (n != kPositionColumns && n != kOrientationColumns) {
      return fail(ErrorCode::kFormat, line_prefix +
                                          "expected 4 values (time x y z) or 8 (time x y "
                                          "z qw qx qy qz), found " +
                                          std::to_string(n));
    }
    if (columns == 0) {
      columns = n;
    } else if (n != columns) {
      return fail(ErrorCode::kFormat, line_prefix + "expected " + std::to_string(columns) +
                                          " values like the first sample, found " +
                                          std::to_string(n));
    }
    auto sample = makeSample(values, n, samples, line_prefix, fields[0]);
    if (!sample) {
      return Unexpected(std::move(sample).error());
    }
    samples.push_back(*sample);
  }
  if (samples.empty()) {
    return fail(ErrorCode::kFormat, path + ": the trajectory has no samples");
  }
  return fromSamples(std::move(samples), columns == kOrientationColumns, path);
}

std::optional<Pose> Trajectory::poseAt(double time_s, std::size_t& segment_hint) const noexcept {
  if (!covers(time_s)) {
    return std::nullopt;
  }
  // Find i, the last sample with time <= time_s: the hint, its successor, or a binary search.
  const std::size_t n = samples_.size();
  const auto isLastAtOrBefore = [&](std::size_t i) {
    return i < n && samples_[i].time_s <= time_s && (i + 1 == n || time_s < samples_[i + 1].time_s);
  };
  std::size_t i = segment_hint;
  if (!isLastAtOrBefore(i)) {
    if (isLastAtOrBefore(i + 1)) {
      ++i;
    } else {
      const auto after = std::upper_bound(
          samples_.begin(), samples_.end(), time_s,
          [](double t, const TrajectorySample& sample) { return t < sample.time_s; });
      i = static_cast<std::size_t>(after - samples_.begin()) - 1;
    }
  }
  segment_hint = i;
  const TrajectorySample& a = samples_[i];
  if (a.time_s == time_s) {
    return Pose{a.position, a.orientation};  // exact, free of interpolation rounding
  }
  const TrajectorySample& b = samples_[i + 1];  // exists: time_s < endTime() here
  const double f = (time_s - a.time_s) / (b.time_s - a.time_s);
  // Orientations are the identity throughout when the file has none, so nlerp keeps them so.
  return interpolate(Pose{a.position, a.orientation}, Pose{b.position, b.orientation}, f);
}

rm_pose toRmPose(const Pose& pose) noexcept {
  const Eigen::Quaterniond& q = pose.orientation;
  return rm_pose{rm_vec3d{pose.position.x(), pose.position.y(), pose.position.z()},
                 rm_quat{q.w(), q.x(), q.y(), q.z()}};
}

Pose fromRmPose(const rm_pose& pose) noexcept {
  const rm_quat& q = pose.orientation;
  return Pose{Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z),
              Eigen::Quaterniond(q.w, q.x, q.y, q.z)};
}

Pose compose(const Pose& a_b, const Pose& b_c) noexcept {
  return fromRmPose(rm_pose_compose(toRmPose(a_b), toRmPose(b_c)));
}

Pose interpolate(const Pose& a, const Pose& b, double f) noexcept {
  // Not Eigen's slerp: nlerp is what the pose samples have always been interpolated with.
  return fromRmPose(rm_pose_interpolate(toRmPose(a), toRmPose(b), f));
}

Expected<void, Error> saveTrajectory(const Trajectory& trajectory, const std::string& path) {
  auto file = AtomicFileWriter::open(path);
  if (!file) {
    return Unexpected(std::move(file).error());
  }
  const bool oriented = trajectory.hasOrientation();
  std::string text = oriented ? "# time x y z qw qx qy qz\n" : "# time x y z\n";
  constexpr std::size_t kFlushBytes = std::size_t{1} << 16;
  for (const TrajectorySample& s : trajectory.samples()) {
    char line[256];
    int n = std::snprintf(line, sizeof(line), "%.17g %.17g %.17g %.17g", s.time_s, s.position.x(),
                          s.position.y(), s.position.z());
    if (oriented) {
      n += std::snprintf(line + n, sizeof(line) - static_cast<std::size_t>(n),
                         " %.17g %.17g %.17g %.17g", s.orientation.w(), s.orientation.x(),
                         s.orientation.y(), s.orientation.z());
    }
    text.append(line, static_cast<std::size_t>(n));
    text += '\n';
    if (text.size() >= kFlushBytes) {
      if (auto ok = file->write(text); !ok) {
        return ok;
      }
      text.clear();
    }
  }
  if (auto ok = file->write(text); !ok) {
    return ok;
  }
  return file->commit();
}

}  // namespace raymap::io
