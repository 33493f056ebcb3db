// SPDX-License-Identifier: BSD-3-Clause
// Saving and loading .rmap map files: header, per-region zlib blocks, region index and footer, all
// little-endian and checksummed (layout in docs/map-format.md).
#include "src/io/map_file.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <span>
#include <string_view>
#include <tuple>
#include <unordered_set>

#include <zlib.h>

#include "platform/errno_text.hpp"
#include "src/core/byte_order.hpp"
#include "src/core/crc32.hpp"
#include "src/io/atomic_file.hpp"
#include "src/io/layer_values.hpp"
#include "src/map/region_planes.hpp"

namespace raymap::io {
namespace {

// ---- format constants (see docs/map-format.md; changing any of them needs a version bump) ----

// PNG-style magic: a name, then CR LF, SUB, LF so that text-mode transfers and `type` on old
// systems show up as a bad magic instead of a subtly corrupt map.
constexpr std::array<std::uint8_t, 8> kMagic = {'R', 'M', 'A', 'P', '\r', '\n', 0x1A, '\n'};

/// Four ASCII characters as the little-endian u32 that spells them in the file.
constexpr std::uint32_t fourCc(const char (&text)[5]) noexcept {
  const std::array<std::byte, 4> bytes{
      static_cast<std::byte>(text[0]), static_cast<std::byte>(text[1]),
      static_cast<std::byte>(text[2]), static_cast<std::byte>(text[3])};
  return loadLe<std::uint32_t>(bytes.data());
}
constexpr std::uint32_t kRegionTag = fourCc("RREG");
constexpr std::uint32_t kIndexTag = fourCc("RIDX");
constexpr std::uint32_t kEndTag = fourCc("REND");

constexpr std::size_t kPrefixBytes = 16;       // magic, version, header body size
constexpr std::size_t kBlockHeaderBytes = 32;  // tag, coord, raw size, packed size, 2 CRCs
constexpr std::size_t kIndexEntryBytes = 20;   // coord, u64 block offset
constexpr std::size_t kIndexFixedBytes = 8;    // tag + CRC
constexpr std::size_t kFooterBytes = 24;       // tag, u64 region count, u64 index offset, CRC
constexpr std::size_t kZlibOverheadBytes = 6;  // zlib header (2) + Adler-32 trailer (4)
// Deflate cannot do better than about 1032:1; 2048:1 is a safe lower bound on a block's size,
// used to reject a region count that the rest of the file cannot possibly hold.
constexpr std::uint64_t kDeflateMaxRatio = 2048;

// Sane limits, enforced on save (so we never write what we cannot read) and on load (so a
// corrupt size never drives an allocation).
constexpr std::size_t kMaxHeaderBodyBytes = std::size_t{16} << 20;
constexpr std::size_t kMaxInfoItems = 4096;
constexpr std::size_t kMaxInfoKeyBytes = 1024;
constexpr std::size_t kMaxInfoValueBytes = std::size_t{1} << 20;
constexpr std::size_t kMaxLayerNameBytes = 64;

// Version 2 appends the map mode and the NDT parameters to the header body (after the region
// count, so every version-1 offset is unchanged). The block carries its own size so that a damaged
// or foreign block is named as such instead of being read as other fields.
constexpr std::uint32_t kFirstVersionWithMode = 2;
constexpr std::uint16_t kNdtBlockBytes = 5 * 8 + 3 * 4;  // 5 f64, 3 u32 (docs/map-format.md)
constexpr std::uint32_t kNdtFlagAdaptationRate = 1u;     // adaptation rate given, not derived
constexpr std::uint32_t kNdtKnownFlags = kNdtFlagAdaptationRate;
// Version 3 appends the TSDF parameters (after the NDT block): u16 block size, u16 reserved,
// then truncation (m), max weight and drop-off (m) as f64, resolved (never "unset").
constexpr std::uint32_t kFirstVersionWithTsdf = 3;
constexpr std::uint16_t kTsdfBlockBytes = 3 * 8;
constexpr std::uint64_t kMaxRegions = std::numeric_limits<std::uint32_t>::max() / 4u;
// A version beyond the current one by more than this is called what it more likely is: a
// damaged or foreign file (whose checksum happens to match), not a future raymap's map.
constexpr std::uint32_t kPlausibleVersionsAhead = 16;

// ---- little-endian fields (src/core/byte_order.hpp: right whatever the host's byte order) ----
// Written with LeWriter; read with ByteReader.

/// Bounds-checked little-endian reads over a byte span; every getter fails instead of overrunning.
class ByteReader {
 public:
  explicit ByteReader(std::span<const std::byte> bytes) noexcept : bytes_(bytes) {}

  std::size_t remaining() const noexcept { return bytes_.size() - pos_; }
  std::size_t position() const noexcept { return pos_; }

  bool u8(std::uint8_t& v) noexcept { return get(v); }
  bool u16(std::uint16_t& v) noexcept { return get(v); }
  bool u32(std::uint32_t& v) noexcept { return get(v); }
  bool u64(std::uint64_t& v) noexcept { return get(v); }
  bool i32(std::int32_t& v) noexcept { return get(v); }
  bool f32(float& v) noexcept { return get(v); }
  bool f64(double& v) noexcept { return get(v); }
  bool text(std::size_t length, std::string& out) {
    if (length > remaining()) {
      return false;
    }
    out.assign(reinterpret_cast<const char*>(bytes_.data() + pos_), length);
    pos_ += length;
    return true;
  }

 private:
  /// Reads the next T into `v`; false (and `v` zero) when fewer than sizeof(T) bytes are left.
  template <ByteValue T>
  bool get(T& v) noexcept {
    if (sizeof(T) > remaining()) {
      v = T{};
      return false;
    }
    v = loadLe<T>(bytes_.data() + pos_);
    pos_ += sizeof(T);
    return true;
  }

  std::span<const std::byte> bytes_;
  std::size_t pos_ = 0;
};

// ---- the layers of a file ----

/// The saved layers a configuration implies, in schema order (the scan-mark scratch layer is not
/// saved).
std::vector<LayerSpec> savedLayersOf(const LayerSchema& schema) {
  std::vector<LayerSpec> specs;
  for (int i = 0; i < schema.size(); ++i) {
    if (schema.at(i).saved) {
      specs.push_back(schema.at(i));
    }
  }
  return specs;
}

std::uint64_t rawRegionBytes(std::span<const LayerSpec> layers, std::uint32_t voxels) noexcept {
  std::uint64_t bytes = 0;
  for (const LayerSpec& spec : layers) {
    bytes += std::uint64_t{spec.bytes_per_voxel} * voxels;
  }
  return bytes;
}

/// The smallest block (block header + zlib stream) a region of `raw_bytes` can take on disk,
/// plus its index entry.
std::uint64_t minBytesPerRegion(std::uint64_t raw_bytes) noexcept {
  return kBlockHeaderBytes + kZlibOverheadBytes + raw_bytes / kDeflateMaxRatio + kIndexEntryBytes;
}

// Region payload: for each saved layer in order, the layer's byte planes (src/map/region_planes).

// ---- reading ----

struct FileCloser {
  void operator()(std::FILE* file) const noexcept { std::fclose(file); }
};

/// Sequential reads of a file whose size is known up front, so that every declared size can be
/// checked against what is left before anything is allocated or read.
class FileReader {
 public:
  static Result<FileReader> open(const std::string& path) {
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(status)) {
      return fail(ErrorCode::kIo,
                  path + ": cannot open: " + (ec ? ec.message() : std::string("no such file")));
    }
    if (!std::filesystem::is_regular_file(status)) {
      return fail(ErrorCode::kIo, path + ": cannot open: not a regular file");
    }
    std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
    if (!file) {
      return fail(ErrorCode::kIo, path + ": cannot open: " + platform::errnoText(errno));
    }
    const std::uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) {
      return fail(ErrorCode::kIo, path + ": cannot read its size: " + ec.message());
    }
    return FileReader(path, std::move(file), size);
  }

  std::uint64_t size() const noexcept { return size_; }
  std::uint64_t offset() const noexcept { return offset_; }
  std::uint64_t remaining() const noexcept { return size_ - offset_; }

  /// Reads exactly out.size() bytes. @pre out.size() <= remaining()
  Expected<void, Error> read(std::span<std::byte> out) {
    if (out.empty()) {
      return {};
    }
    if (std::fread(out.data(), 1, out.size(), file_.get()) != out.size()) {
      // Sizes were checked against the file size first, so a short read is an I/O error or a
      // file that shrank while we read it.
      const bool eof = std::feof(file_.get()) != 0;
      return fail(eof ? ErrorCode::kTruncated : ErrorCode::kIo,
                  path_ + ": read failed at offset " + std::to_string(offset_) + ": " +
                      (eof ? std::string("unexpected end of file") : platform::errnoText(errno)));
    }
    offset_ += out.size();
    return {};
  }

 private:
  FileReader(std::string path, std::unique_ptr<std::FILE, FileCloser> file,
             std::uint64_t size) noexcept
      : path_(std::move(path)), file_(std::move(file)), size_(size) {}

  std::string path_;
  std::unique_ptr<std::FILE, FileCloser> file_;
  std::uint64_t size_ = 0;
  std::uint64_t offset_ = 0;
};

/// What the header parser hands to the region reader.
struct ParsedHeader {
  MapFileHeader header;
  std::vector<LayerSpec> layers;  ///< saved layers, in file order
  std::uint64_t raw_region_bytes = 0;
};

std::string describeLayer(std::size_t index, std::uint8_t kind, const std::string& name) {
  return "layer " + std::to_string(index + 1) + " (kind " + std::to_string(kind) + ", '" + name +
         "')";
}

/// Version 2: the map mode and the NDT block. `malformed` builds the error (it names the file and
/// the header offset).
template <class Malformed>
Expected<void, Error> readModeAndNdt(ByteReader& body, MapConfig& config,
                                     const Malformed& malformed) {
  std::uint8_t mode = 0;
  std::uint8_t reserved = 0;
  std::uint16_t block_bytes = 0;
  if (!body.u8(mode) || !body.u8(reserved) || !body.u16(block_bytes)) {
    return malformed("map mode runs past the header");
  }
  if (mode > static_cast<std::uint8_t>(MapMode::kTsdf) || reserved != 0) {
    return malformed("unknown map mode " + std::to_string(mode));
  }
  if (block_bytes != kNdtBlockBytes) {
    return malformed("NDT parameter block of " + std::to_string(block_bytes) + " bytes (expected " +
                     std::to_string(kNdtBlockBytes) + ")");
  }
  NdtParams& ndt = config.ndt;
  double adaptation_rate = 0.0;
  std::uint32_t flags = 0;
  if (!body.f64(ndt.sensor_noise) || !body.f64(ndt.regulariser) ||
      !body.f64(ndt.reinit_probability) || !body.f64(adaptation_rate) ||
      !body.f64(ndt.initial_intensity_variance) || !body.u32(ndt.sample_threshold) ||
      !body.u32(ndt.reinit_count) || !body.u32(flags)) {
    return malformed("NDT parameters run past the header");
  }
  if ((flags & ~kNdtKnownFlags) != 0) {
    return malformed("unknown NDT flags " + std::to_string(flags));
  }
  ndt.adaptation_rate.reset();
  if ((flags & kNdtFlagAdaptationRate) != 0) {
    ndt.adaptation_rate = adaptation_rate;
  }
  config.mode = static_cast<MapMode>(mode);
  if (auto ok = ndt.validate(); !ok) {
    return malformed("bad NDT parameters: " + ok.error().message);
  }
  return {};
}

/// Version 3: the TSDF block. `malformed` builds the error.
template <class Malformed>
Expected<void, Error> readTsdf(ByteReader& body, MapConfig& config, const Malformed& malformed) {
  std::uint16_t block_bytes = 0;
  std::uint16_t reserved = 0;
  if (!body.u16(block_bytes) || !body.u16(reserved)) {
    return malformed("TSDF parameters run past the header");
  }
  if (block_bytes != kTsdfBlockBytes || reserved != 0) {
    return malformed("TSDF parameter block of " + std::to_string(block_bytes) +
                     " bytes (expected " + std::to_string(kTsdfBlockBytes) + ")");
  }
  double truncation = 0.0;
  double dropoff = 0.0;
  TsdfParams& tsdf = config.tsdf;
  if (!body.f64(truncation) || !body.f64(tsdf.max_weight) || !body.f64(dropoff)) {
    return malformed("TSDF parameters run past the header");
  }
  tsdf.truncation_m = truncation;
  tsdf.dropoff_m = dropoff;
  if (auto ok = tsdf.validate(config.geometry.resolution); !ok) {
    return malformed("bad TSDF parameters: " + ok.error().message);
  }
  return {};
}

/// The header's bytes once its magic, size, checksum and version have been checked.
struct CheckedHeader {
  std::vector<std::byte> bytes;  ///< prefix, body and checksum
  std::uint32_t version = 0;
  std::uint32_t body_bytes = 0;
};

/// Reads the fixed prefix (magic, version, body size) and checks the magic.
Result<std::array<std::byte, kPrefixBytes>> readPrefix(FileReader& file, const std::string& path) {
  if (file.size() == 0) {
    return fail(ErrorCode::kFormat, path + " is empty (0 bytes): not a raymap map file");
  }
  std::array<std::byte, kPrefixBytes> prefix{};
  const std::size_t prefix_bytes =
      static_cast<std::size_t>(std::min<std::uint64_t>(file.size(), kPrefixBytes));
  if (auto ok = file.read(std::span(prefix).first(prefix_bytes)); !ok) {
    return Unexpected(ok.error());
  }
  const std::size_t magic_bytes = std::min(prefix_bytes, kMagic.size());
  for (std::size_t i = 0; i < magic_bytes; ++i) {
    if (std::to_integer<std::uint8_t>(prefix[i]) != kMagic[i]) {
      return fail(ErrorCode::kFormat, path + ": not a raymap map file (bad magic)");
    }
  }
  if (prefix_bytes < kPrefixBytes) {
    return fail(ErrorCode::kTruncated, path + ": truncated in the header (file is " +
                                           std::to_string(file.size()) + " bytes)");
  }
  return prefix;
}

std::string versionsRead() { return "versions 1 to " + std::to_string(kMapFormatVersion); }

/// A header whose checksum matched: is its version one this raymap reads?
Expected<void, Error> checkVersion(std::uint32_t version, const std::string& path) {
  if (version > kMapFormatVersion + kPlausibleVersionsAhead) {
    return fail(ErrorCode::kUnsupported,
                path + ": unsupported map format version " + std::to_string(version) +
                    " (this raymap reads " + versionsRead() +
                    "); a version this far ahead is more likely a damaged or foreign file than "
                    "a newer raymap's");
  }
  if (version > kMapFormatVersion) {
    return fail(ErrorCode::kUnsupported, path + ": map format version " + std::to_string(version) +
                                             " is newer than this raymap, which reads " +
                                             versionsRead());
  }
  if (version == 0) {
    return fail(ErrorCode::kCorrupt, path + ": invalid map format version 0");
  }
  return {};
}

/// Reads the whole header and checks its size, checksum and version; the body is not parsed.
Result<CheckedHeader> readCheckedHeader(FileReader& file, const std::string& path) {
  auto prefix = readPrefix(file, path);
  if (!prefix) {
    return Unexpected(prefix.error());
  }
  CheckedHeader checked;
  ByteReader prefix_reader{std::span(*prefix).subspan(kMagic.size())};
  (void)prefix_reader.u32(checked.version);
  (void)prefix_reader.u32(checked.body_bytes);
  const std::uint32_t version = checked.version;
  const std::uint32_t body_bytes = checked.body_bytes;
  // The header checksum covers the version, so it is checked first: a damaged version field is
  // damage, not a newer format. Only a header too large or cut short to check is judged by its
  // version alone.
  const bool newer = version > kMapFormatVersion;
  const auto unchecked_newer = [&] {
    return fail(ErrorCode::kUnsupported,
                path + ": map format version " + std::to_string(version) +
                    " is newer than this raymap, which reads " + versionsRead() +
                    " (or the file is damaged: its header cannot be checked)");
  };
  if (body_bytes > kMaxHeaderBodyBytes) {
    if (newer) {
      return unchecked_newer();
    }
    return fail(ErrorCode::kCorrupt, path + ": header declares " + std::to_string(body_bytes) +
                                         " bytes (limit " + std::to_string(kMaxHeaderBodyBytes) +
                                         ")");
  }
  if (std::uint64_t{body_bytes} + 4u > file.remaining()) {
    if (newer) {
      return unchecked_newer();
    }
    return fail(ErrorCode::kTruncated, path + ": truncated in the header (file is " +
                                           std::to_string(file.size()) + " bytes, header needs " +
                                           std::to_string(kPrefixBytes + body_bytes + 4u) + ")");
  }
  checked.bytes.resize(kPrefixBytes + body_bytes + 4u);
  std::copy(prefix->begin(), prefix->end(), checked.bytes.begin());
  if (auto ok = file.read(std::span(checked.bytes).subspan(kPrefixBytes)); !ok) {
    return Unexpected(ok.error());
  }
  std::uint32_t stored_crc = 0;
  (void)ByteReader(std::span(checked.bytes).last(4)).u32(stored_crc);
  if (crc32(0, std::span(checked.bytes).first(kPrefixBytes + body_bytes)) != stored_crc) {
    if (newer || version == 0) {
      return fail(ErrorCode::kCorrupt, path +
                                           ": damaged header: its checksum does not match, and "
                                           "its version field reads " +
                                           std::to_string(version) +
                                           " (this raymap reads map format " + versionsRead() +
                                           ")");
    }
    return fail(ErrorCode::kCorrupt, path + ": header checksum mismatch");
  }
  if (auto ok = checkVersion(version, path); !ok) {
    return Unexpected(ok.error());
  }
  return checked;
}

/// The map parameters: geometry, occupancy, semantics, voxel mean. Leaves the layer count.
template <class Malformed>
Expected<void, Error> readMapParameters(ByteReader& body, MapConfig& config,
                                        std::uint16_t& layer_count, const std::string& path,
                                        const Malformed& malformed) {
  std::uint8_t semantics = 0;
  std::uint8_t voxel_mean = 0;
  if (!body.f64(config.geometry.resolution) || !body.i32(config.geometry.region_voxels) ||
      !body.f32(config.occupancy.hit) || !body.f32(config.occupancy.miss) ||
      !body.f32(config.occupancy.clamp_min) || !body.f32(config.occupancy.clamp_max) ||
      !body.f32(config.occupancy.threshold) || !body.u8(semantics) || !body.u8(voxel_mean) ||
      !body.u16(layer_count)) {
    return malformed("map parameters run past the header");
  }
  if (semantics > static_cast<std::uint8_t>(Semantics::kPerScan)) {
    return malformed("unknown semantics " + std::to_string(semantics));
  }
  if (voxel_mean > 1) {
    return malformed("voxel-mean flag is " + std::to_string(voxel_mean) + ", not 0 or 1");
  }
  config.semantics = static_cast<Semantics>(semantics);
  config.voxel_mean = voxel_mean != 0;
  config.policy = StorePolicy::kGlobal;
  if (auto ok = config.geometry.validate(); !ok) {
    return fail(ErrorCode::kCorrupt, path + ": bad map parameters: " + ok.error().message);
  }
  if (auto ok = config.occupancy.validate(); !ok) {
    return fail(ErrorCode::kCorrupt, path + ": bad map parameters: " + ok.error().message);
  }
  return {};
}

/// One layer entry `index`: a layer this raymap knows, in its current encoding, as defined.
template <class Malformed>
Result<LayerSpec> readLayer(ByteReader& body, std::size_t index, const std::string& path,
                            const Malformed& malformed) {
  std::uint8_t kind = 0;
  std::uint8_t reserved = 0;
  std::uint16_t layer_version = 0;
  std::uint32_t bytes_per_voxel = 0;
  std::uint16_t name_bytes = 0;
  std::string name;
  if (!body.u8(kind) || !body.u8(reserved) || !body.u16(layer_version) ||
      !body.u32(bytes_per_voxel) || !body.u16(name_bytes)) {
    return malformed("layer " + std::to_string(index + 1) + " runs past the header");
  }
  if (name_bytes > kMaxLayerNameBytes || !body.text(name_bytes, name)) {
    return malformed("layer " + std::to_string(index + 1) + " has a bad name length");
  }
  const std::optional<LayerSpec> spec = layerSpec(static_cast<LayerKind>(kind));
  if (!spec) {
    return fail(ErrorCode::kUnsupported,
                path + ": " + describeLayer(index, kind, name) + " is unknown to this raymap");
  }
  if (layer_version > spec->version) {
    return fail(ErrorCode::kUnsupported,
                path + ": " + describeLayer(index, kind, name) + " has encoding version " +
                    std::to_string(layer_version) + ", newer than this raymap (" +
                    std::to_string(spec->version) + ")");
  }
  if (layer_version != spec->version) {
    return fail(ErrorCode::kUnsupported,
                path + ": " + describeLayer(index, kind, name) + " has old encoding version " +
                    std::to_string(layer_version) + " that this raymap cannot convert");
  }
  if (!spec->saved || name != spec->name || bytes_per_voxel != spec->bytes_per_voxel ||
      reserved != 0) {
    return malformed(describeLayer(index, kind, name) + " does not match its definition ('" +
                     std::string(spec->name) + "', " + std::to_string(spec->bytes_per_voxel) +
                     " bytes per voxel)");
  }
  return *spec;
}

/// The layer list; a map saved without its occupancy layer, or with a traversal layer, says so
/// by the list alone.
template <class Malformed>
Expected<void, Error> readLayers(ByteReader& body, std::uint16_t layer_count, ParsedHeader& parsed,
                                 const std::string& path, const Malformed& malformed) {
  if (layer_count > LayerSchema::kMaxLayers) {
    return malformed(std::to_string(layer_count) + " layers (at most " +
                     std::to_string(LayerSchema::kMaxLayers) + ")");
  }
  for (std::size_t i = 0; i < layer_count; ++i) {
    auto spec = readLayer(body, i, path, malformed);
    if (!spec) {
      return Unexpected(spec.error());
    }
    parsed.header.saved_layers.push_back(spec->kind);
    parsed.layers.push_back(*spec);
  }
  const auto has_layer = [&parsed](LayerKind kind) {
    return std::any_of(parsed.layers.begin(), parsed.layers.end(),
                       [kind](const LayerSpec& spec) { return spec.kind == kind; });
  };
  parsed.header.config.occupancy_layer = has_layer(LayerKind::kOccupancy);
  parsed.header.config.decay_rate = has_layer(LayerKind::kTraversal);
  return {};
}

/// The info items (provenance: key and value texts), then the region count.
template <class Malformed>
Expected<void, Error> readInfoAndRegionCount(ByteReader& body, MapFileHeader& out,
                                             const Malformed& malformed) {
  std::uint32_t info_count = 0;
  if (!body.u32(info_count)) {
    return malformed("info count runs past the header");
  }
  if (info_count > kMaxInfoItems) {
    return malformed(std::to_string(info_count) + " info items (at most " +
                     std::to_string(kMaxInfoItems) + ")");
  }
  for (std::uint32_t i = 0; i < info_count; ++i) {
    std::uint32_t key_bytes = 0;
    std::uint32_t value_bytes = 0;
    std::string key;
    std::string value;
    if (!body.u32(key_bytes) || key_bytes > kMaxInfoKeyBytes || !body.text(key_bytes, key) ||
        !body.u32(value_bytes) || value_bytes > kMaxInfoValueBytes ||
        !body.text(value_bytes, value)) {
      return malformed("info item " + std::to_string(i + 1) + " is malformed");
    }
    out.info.emplace_back(std::move(key), std::move(value));
  }
  if (!body.u64(out.region_count)) {
    return malformed("region count runs past the header");
  }
  return {};
}

/// The mode's constraints, and the layers the parameters imply, in that order: the voxels are
/// only meaningful with those.
template <class Malformed>
Expected<void, Error> checkModeAndLayers(const ParsedHeader& parsed, const Malformed& malformed) {
  const MapConfig& config = parsed.header.config;
  if (isNdt(config.mode) && config.semantics != Semantics::kPerRay) {
    return malformed(std::string(toString(config.mode)) + " map with per-scan semantics");
  }
  if (isNdt(config.mode) && !config.occupancy_layer) {
    return malformed(std::string(toString(config.mode)) + " map without an occupancy layer");
  }
  const std::vector<LayerSpec> expected = savedLayersOf(config.schema());
  bool layers_match = expected.size() == parsed.layers.size();
  for (std::size_t i = 0; layers_match && i < expected.size(); ++i) {
    layers_match = expected[i].kind == parsed.layers[i].kind;
  }
  if (!layers_match) {
    return malformed("the saved layers do not match the map parameters (" +
                     std::string(toString(config.mode)) + " map)");
  }
  return {};
}

/// Before the pool is sized from the region count: the rest of the file must be able to hold
/// that many regions. Then just enough pool for them (at least one: a map always holds a region).
Expected<void, Error> sizeRegions(const FileReader& file, ParsedHeader& parsed,
                                  const std::string& path) {
  MapFileHeader& out = parsed.header;
  if (out.region_count > kMaxRegions) {
    return fail(ErrorCode::kCorrupt, path + ": header declares " +
                                         std::to_string(out.region_count) + " regions (at most " +
                                         std::to_string(kMaxRegions) + ")");
  }
  const std::uint32_t voxels = out.config.geometry.voxelsPerRegion();
  parsed.raw_region_bytes = rawRegionBytes(parsed.layers, voxels);
  if (parsed.raw_region_bytes > std::numeric_limits<std::uint32_t>::max()) {
    return fail(
        ErrorCode::kUnsupported,
        path + ": regions of " + std::to_string(parsed.raw_region_bytes) + " bytes are too large");
  }
  const std::uint64_t needed = out.region_count * minBytesPerRegion(parsed.raw_region_bytes) +
                               kIndexFixedBytes + kFooterBytes;
  if (needed > file.remaining()) {
    return fail(ErrorCode::kTruncated,
                path + ": truncated: the header declares " + std::to_string(out.region_count) +
                    " regions, which need at least " + std::to_string(needed) + " bytes, but " +
                    std::to_string(file.remaining()) + " follow the header");
  }
  const std::uint64_t per_region = out.config.schema().bytesPerRegion(voxels);
  out.config.memory_budget_bytes = std::max<std::uint64_t>(out.region_count, 1) * per_region;
  return {};
}

/// Parses and checks the header; on success the reader is at the first region block.
Result<ParsedHeader> readHeader(FileReader& file, const std::string& path) {
  auto checked = readCheckedHeader(file, path);
  if (!checked) {
    return Unexpected(checked.error());
  }
  const std::uint32_t version = checked->version;
  // The body is covered by the CRC, so a failed check below is a writer bug or a forged file;
  // it still never reads out of bounds.
  ByteReader body{std::span(checked->bytes).subspan(kPrefixBytes, checked->body_bytes)};
  const auto malformed = [&](const std::string& what) {
    return fail(ErrorCode::kCorrupt, path + ": malformed header: " + what + " (header offset " +
                                         std::to_string(kPrefixBytes + body.position()) + ")");
  };
  ParsedHeader parsed;
  parsed.header.format_version = version;
  MapConfig& config = parsed.header.config;
  std::uint16_t layer_count = 0;
  if (auto ok = readMapParameters(body, config, layer_count, path, malformed); !ok) {
    return Unexpected(ok.error());
  }
  if (auto ok = readLayers(body, layer_count, parsed, path, malformed); !ok) {
    return Unexpected(ok.error());
  }
  if (auto ok = readInfoAndRegionCount(body, parsed.header, malformed); !ok) {
    return Unexpected(ok.error());
  }
  if (version >= kFirstVersionWithMode) {
    if (auto ok = readModeAndNdt(body, config, malformed); !ok) {
      return Unexpected(ok.error());
    }
  }  // else a version-1 file: an occupancy map, whose NDT parameters stay at their defaults
  if (version >= kFirstVersionWithTsdf) {
    if (auto ok = readTsdf(body, config, malformed); !ok) {
      return Unexpected(ok.error());
    }
  }  // else no TSDF map: its parameters stay at their defaults
  if (auto ok = checkModeAndLayers(parsed, malformed); !ok) {
    return Unexpected(ok.error());
  }
  if (body.remaining() != 0) {
    return malformed(std::to_string(body.remaining()) + " unexpected bytes at the end");
  }
  if (auto ok = sizeRegions(file, parsed, path); !ok) {
    return Unexpected(ok.error());
  }
  return parsed;
}

struct IndexEntry {
  Vec3i coord;
  std::uint64_t offset = 0;
};

/// NaN, inf or -inf as messages spell them.
std::string valueText(float value) {
  if (std::isnan(value)) {
    return "NaN";
  }
  return value > 0.0f ? "inf" : "-inf";
}

std::string coordText(Vec3i c) {
  // snprintf, not string concatenation: GCC 12 at -O3 reports a false -Wrestrict on
  // `"(" + std::to_string(...)`.
  char text[48];
  std::snprintf(text, sizeof(text), "(%d, %d, %d)", c.x, c.y, c.z);
  return text;
}

/// Reads and checks the region index and the footer that follow the last block.
Expected<void, Error> readTrailer(FileReader& file, const std::string& path,
                                  std::span<const IndexEntry> blocks) {
  const std::uint64_t index_offset = file.offset();
  const std::uint64_t index_bytes = kIndexFixedBytes + blocks.size() * kIndexEntryBytes;
  if (index_bytes + kFooterBytes > file.remaining()) {
    return fail(ErrorCode::kTruncated, path + ": truncated in the region index (offset " +
                                           std::to_string(index_offset) + ")");
  }
  std::vector<std::byte> index(static_cast<std::size_t>(index_bytes));
  if (auto ok = file.read(index); !ok) {
    return ok;
  }
  ByteReader reader(index);
  std::uint32_t tag = 0;
  (void)reader.u32(tag);
  if (tag != kIndexTag) {
    return fail(ErrorCode::kCorrupt, path + ": no region index at offset " +
                                         std::to_string(index_offset) + " (bad marker)");
  }
  std::uint32_t index_crc = 0;
  (void)ByteReader(std::span(index).last(4)).u32(index_crc);
  if (crc32(0, std::span(index).first(index.size() - 4)) != index_crc) {
    return fail(ErrorCode::kCorrupt, path + ": region index checksum mismatch (offset " +
                                         std::to_string(index_offset) + ")");
  }
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    IndexEntry entry;
    (void)reader.i32(entry.coord.x);
    (void)reader.i32(entry.coord.y);
    (void)reader.i32(entry.coord.z);
    (void)reader.u64(entry.offset);
    if (entry.coord != blocks[i].coord || entry.offset != blocks[i].offset) {
      return fail(ErrorCode::kCorrupt, path + ": region index entry " + std::to_string(i + 1) +
                                           " does not match the region blocks");
    }
  }

  const std::uint64_t footer_offset = file.offset();
  std::array<std::byte, kFooterBytes> footer{};
  if (auto ok = file.read(footer); !ok) {
    return ok;
  }
  ByteReader footer_reader(footer);
  std::uint32_t end_tag = 0;
  std::uint64_t count = 0;
  std::uint64_t stored_index_offset = 0;
  std::uint32_t footer_crc = 0;
  (void)footer_reader.u32(end_tag);
  (void)footer_reader.u64(count);
  (void)footer_reader.u64(stored_index_offset);
  (void)footer_reader.u32(footer_crc);
  if (end_tag != kEndTag) {
    return fail(ErrorCode::kCorrupt,
                path + ": no end marker at offset " + std::to_string(footer_offset));
  }
  if (crc32(0, std::span(footer).first(kFooterBytes - 4)) != footer_crc) {
    return fail(ErrorCode::kCorrupt, path + ": end marker checksum mismatch (offset " +
                                         std::to_string(footer_offset) + ")");
  }
  if (count != blocks.size() || stored_index_offset != index_offset) {
    return fail(ErrorCode::kCorrupt, path + ": end marker does not match the file (" +
                                         std::to_string(count) + " regions, index at " +
                                         std::to_string(stored_index_offset) + ")");
  }
  if (file.remaining() != 0) {
    return fail(ErrorCode::kCorrupt, path + ": " + std::to_string(file.remaining()) +
                                         " unexpected bytes after the end marker");
  }
  return {};
}

/// One region block's header, checked: its marker and checksum, sizes the file can hold, and a
/// coordinate in range.
struct BlockHeader {
  Vec3i coord;
  std::uint32_t packed_bytes = 0;
  std::uint32_t payload_crc = 0;
};

/// Where a block is, for messages: "PATH: region R of N (offset X)".
struct BlockPlace {
  const std::string& path;
  std::uint64_t index = 0;  ///< from 0
  std::uint64_t count = 0;
  std::uint64_t offset = 0;
  std::string where() const {
    return path + ": region " + std::to_string(index + 1) + " of " + std::to_string(count) +
           " (offset " + std::to_string(offset) + ")";
  }
  Unexpected<Error> truncated() const {
    return fail(ErrorCode::kTruncated, path + ": truncated in region " + std::to_string(index + 1) +
                                           " of " + std::to_string(count) + " (offset " +
                                           std::to_string(offset) + ")");
  }
};

Result<BlockHeader> readBlockHeader(FileReader& file, const BlockPlace& place,
                                    std::size_t raw_bytes, std::uint64_t max_packed) {
  if (kBlockHeaderBytes > file.remaining()) {
    return place.truncated();
  }
  std::array<std::byte, kBlockHeaderBytes> head{};
  if (auto ok = file.read(head); !ok) {
    return Unexpected(ok.error());
  }
  ByteReader reader(head);
  BlockHeader block;
  std::uint32_t tag = 0;
  std::uint32_t stored_raw = 0;
  std::uint32_t head_crc = 0;
  (void)reader.u32(tag);
  (void)reader.i32(block.coord.x);
  (void)reader.i32(block.coord.y);
  (void)reader.i32(block.coord.z);
  (void)reader.u32(stored_raw);
  (void)reader.u32(block.packed_bytes);
  (void)reader.u32(block.payload_crc);
  (void)reader.u32(head_crc);
  if (tag != kRegionTag) {
    return fail(ErrorCode::kCorrupt, place.where() + ": bad block marker");
  }
  if (crc32(0, std::span(head).first(kBlockHeaderBytes - 4)) != head_crc) {
    return fail(ErrorCode::kCorrupt, place.where() + ": block header checksum mismatch");
  }
  if (stored_raw != raw_bytes) {
    return fail(ErrorCode::kCorrupt, place.where() + ": holds " + std::to_string(stored_raw) +
                                         " bytes of voxels, expected " + std::to_string(raw_bytes));
  }
  if (block.packed_bytes < kZlibOverheadBytes || block.packed_bytes > max_packed) {
    return fail(ErrorCode::kCorrupt, place.where() + ": compressed size " +
                                         std::to_string(block.packed_bytes) + " is impossible");
  }
  if (block.packed_bytes > file.remaining()) {
    return place.truncated();
  }
  if (!RegionStore::inRange(block.coord)) {
    return fail(ErrorCode::kCorrupt, place.where() + ": region coordinate " +
                                         coordText(block.coord) + " is out of range");
  }
  return block;
}

/// The block's compressed voxels, checked against their checksum and unpacked into `raw`.
Expected<void, Error> readBlockVoxels(FileReader& file, const BlockPlace& place,
                                      const BlockHeader& block, std::vector<std::byte>& packed,
                                      std::vector<std::byte>& raw) {
  packed.resize(block.packed_bytes);
  if (auto ok = file.read(packed); !ok) {
    return ok;
  }
  if (crc32(0, packed) != block.payload_crc) {
    return fail(ErrorCode::kCorrupt, place.where() + ": checksum mismatch");
  }
  uLongf out_bytes = static_cast<uLongf>(raw.size());
  uLong in_bytes = static_cast<uLong>(packed.size());
  const int z = ::uncompress2(reinterpret_cast<Bytef*>(raw.data()), &out_bytes,
                              reinterpret_cast<const Bytef*>(packed.data()), &in_bytes);
  if (z != Z_OK || out_bytes != raw.size() || in_bytes != packed.size()) {
    return fail(ErrorCode::kCorrupt, place.where() + ": compressed voxels do not decode (zlib " +
                                         std::to_string(z) + ")");
  }
  return {};
}

/// Puts the unpacked voxels `raw` of region `coord` into the map, layer by layer
/// (`schema_layers`: each saved layer's index in the map's schema), checking their values.
Expected<void, Error> storeRegion(VoxelMap& map, const ParsedHeader& parsed,
                                  std::span<const int> schema_layers,
                                  std::span<const std::byte> raw, Vec3i coord,
                                  const BlockPlace& place) {
  const std::uint32_t voxels = map.geometry().voxelsPerRegion();
  // A tiered map streams the file through its pool: earlier regions move to the cold tiers.
  map.beginEpoch();
  const auto slot = map.tiered() ? map.acquireRegion(coord) : map.store().findOrCreate(coord);
  if (!slot) {
    // Untiered, the pool was sized for region_count regions: a bug, not a file problem.
    return fail(ErrorCode::kCapacity,
                place.where() + ": cannot store region: " + map.tierError(slot.error()).message);
  }
  std::size_t at = 0;
  for (std::size_t l = 0; l < parsed.layers.size(); ++l) {
    const LayerSpec& spec = parsed.layers[l];
    std::byte* layer = map.store().layerBytes(*slot, schema_layers[l]);
    decodeBytePlanes(raw.data() + at, voxels, spec.bytes_per_voxel / 4u, layer);
    at += std::size_t{spec.bytes_per_voxel} * voxels;
    // The checksums only say the bytes are those written; a forged or buggy writer's NaN
    // would otherwise be taken for a value (a NaN occupancy compares as free).
    if (const auto bad = findBadLayerValue(spec.kind, layer, voxels)) {
      return fail(ErrorCode::kCorrupt,
                  place.path + ": region " + coordText(coord) + " (block " +
                      std::to_string(place.index + 1) + " of " + std::to_string(place.count) +
                      "): layer '" + std::string(spec.name) + "' holds " + valueText(bad->value) +
                      " at voxel " + coordText(map.voxelAt(coord, bad->voxel)) + ", where " +
                      bad->rule + ": the file is damaged or was not written by raymap");
    }
  }
  return {};
}

/// Reads every region block into `map`, then the index and footer.
Expected<void, Error> readRegions(FileReader& file, const std::string& path,
                                  const ParsedHeader& parsed, VoxelMap& map) {
  const std::uint64_t count = parsed.header.region_count;
  const auto raw_bytes = static_cast<std::size_t>(parsed.raw_region_bytes);
  const std::uint64_t max_packed = ::compressBound(static_cast<uLong>(raw_bytes));
  // Each saved layer's index in the map's schema (the file's layers are the schema's saved ones).
  std::vector<int> schema_layers;
  for (const LayerSpec& spec : parsed.layers) {
    schema_layers.push_back(map.store().schema().indexOf(spec.kind));
  }
  std::vector<IndexEntry> blocks;
  blocks.reserve(static_cast<std::size_t>(count));  // bounded by the file size (readHeader)
  std::unordered_set<std::uint64_t> seen;           // tiered maps: the regions read so far
  std::vector<std::byte> packed;
  std::vector<std::byte> raw(raw_bytes);
  for (std::uint64_t r = 0; r < count; ++r) {
    const BlockPlace place{path, r, count, file.offset()};
    auto block = readBlockHeader(file, place, raw_bytes, max_packed);
    if (!block) {
      return Unexpected(block.error());
    }
    const bool duplicate = map.tiered() ? !seen.insert(RegionStore::packCoord(block->coord)).second
                                        : map.store().find(block->coord) != RegionStore::kNoSlot;
    if (duplicate) {
      return fail(ErrorCode::kCorrupt,
                  place.where() + ": duplicate region " + coordText(block->coord));
    }
    if (auto ok = readBlockVoxels(file, place, *block, packed, raw); !ok) {
      return ok;
    }
    if (auto ok = storeRegion(map, parsed, schema_layers, raw, block->coord, place); !ok) {
      return ok;
    }
    blocks.push_back(IndexEntry{block->coord, place.offset});
  }
  return readTrailer(file, path, blocks);
}

// ---- writing ----

Expected<void, Error> checkInfoFits(const VoxelMap& map, const std::string& path) {
  const auto& info = map.info();
  if (info.size() > kMaxInfoItems) {
    return fail(ErrorCode::kInvalidArgument, path + ": " + std::to_string(info.size()) +
                                                 " info items (a map file holds at most " +
                                                 std::to_string(kMaxInfoItems) + ")");
  }
  for (const auto& [key, value] : info) {
    if (key.size() > kMaxInfoKeyBytes || value.size() > kMaxInfoValueBytes) {
      return fail(ErrorCode::kInvalidArgument,
                  path + ": info item '" + key.substr(0, 64) + "' is too long (key at most " +
                      std::to_string(kMaxInfoKeyBytes) + " bytes, value at most " +
                      std::to_string(kMaxInfoValueBytes) + ")");
    }
  }
  return {};
}

std::vector<std::byte> encodeHeader(const VoxelMap& map, std::span<const LayerSpec> layers) {
  LeWriter body;
  const MapConfig& config = map.config();
  body.f64(config.geometry.resolution);
  body.i32(config.geometry.region_voxels);
  body.f32(config.occupancy.hit);
  body.f32(config.occupancy.miss);
  body.f32(config.occupancy.clamp_min);
  body.f32(config.occupancy.clamp_max);
  body.f32(config.occupancy.threshold);
  body.u8(static_cast<std::uint8_t>(config.semantics));
  body.u8(static_cast<std::uint8_t>(config.voxel_mean ? 1 : 0));
  body.u16(static_cast<std::uint16_t>(layers.size()));
  for (const LayerSpec& spec : layers) {
    body.u8(static_cast<std::uint8_t>(spec.kind));
    body.u8(0);  // reserved
    body.u16(spec.version);
    body.u32(spec.bytes_per_voxel);
    body.u16(static_cast<std::uint16_t>(spec.name.size()));
    body.text(spec.name);
  }
  body.u32(static_cast<std::uint32_t>(map.info().size()));
  for (const auto& [key, value] : map.info()) {
    body.u32(static_cast<std::uint32_t>(key.size()));
    body.text(key);
    body.u32(static_cast<std::uint32_t>(value.size()));
    body.text(value);
  }
  body.u64(map.regionCount());  // every tier of a tiered map
  // Version 2: mode and NDT parameters (written for every mode, so a config round-trips whole).
  const NdtParams& ndt = config.ndt;
  body.u8(static_cast<std::uint8_t>(config.mode));
  body.u8(0);  // reserved
  body.u16(kNdtBlockBytes);
  body.f64(ndt.sensor_noise);
  body.f64(ndt.regulariser);
  body.f64(ndt.reinit_probability);
  body.f64(ndt.adaptation_rate.value_or(0.0));
  body.f64(ndt.initial_intensity_variance);
  body.u32(ndt.sample_threshold);
  body.u32(ndt.reinit_count);
  body.u32(ndt.adaptation_rate ? kNdtFlagAdaptationRate : 0u);
  // Version 3: TSDF parameters, resolved for the map's resolution.
  const double resolution = config.geometry.resolution;
  body.u16(kTsdfBlockBytes);
  body.u16(0);  // reserved
  body.f64(config.tsdf.truncationMetres(resolution));
  body.f64(config.tsdf.max_weight);
  body.f64(config.tsdf.dropoffMetres(resolution));

  LeWriter header;
  for (const std::uint8_t b : kMagic) {
    header.u8(b);
  }
  header.u32(kMapFormatVersion);
  header.u32(static_cast<std::uint32_t>(body.bytes().size()));
  header.raw(body.bytes());
  header.u32(crc32(0, header.bytes()));
  return std::move(header.bytes());
}

/// Encodes one region's saved layers into `raw` and compresses them into `packed`.
/// @return the compressed bytes (a prefix of `packed`)
Result<std::span<const std::byte>> packRegion(const RegionStore& store, std::uint32_t slot,
                                              Vec3i coord, std::span<const LayerSpec> layers,
                                              std::span<const int> schema_layers,
                                              std::vector<std::byte>& raw,
                                              std::vector<std::byte>& packed,
                                              const std::string& path) {
  const std::uint32_t voxels = store.voxelsPerRegion();
  std::size_t at = 0;
  for (std::size_t l = 0; l < layers.size(); ++l) {
    encodeBytePlanes(store.layerBytes(slot, schema_layers[l]), voxels,
                     layers[l].bytes_per_voxel / 4u, raw.data() + at);
    at += std::size_t{layers[l].bytes_per_voxel} * voxels;
  }
  uLongf packed_bytes = static_cast<uLongf>(packed.size());
  const int z = ::compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_bytes,
                            reinterpret_cast<const Bytef*>(raw.data()),
                            static_cast<uLong>(raw.size()), Z_BEST_SPEED);
  if (z != Z_OK) {
    return fail(ErrorCode::kIo, path + ": compressing region " + coordText(coord) +
                                    " failed (zlib " + std::to_string(z) + ")");
  }
  return std::span<const std::byte>(packed).first(packed_bytes);
}

/// A region block's header: marker, coordinate, sizes and checksums.
LeWriter blockHeader(Vec3i coord, std::size_t raw_bytes, std::span<const std::byte> payload) {
  LeWriter head;
  head.u32(kRegionTag);
  head.i32(coord.x);
  head.i32(coord.y);
  head.i32(coord.z);
  head.u32(static_cast<std::uint32_t>(raw_bytes));
  head.u32(static_cast<std::uint32_t>(payload.size()));
  head.u32(crc32(0, payload));
  head.u32(crc32(0, head.bytes()));
  return head;
}

/// The region index (its entries already in `index`) and the footer.
Expected<void, Error> writeTrailer(AtomicFileWriter& writer, LeWriter& index,
                                   std::uint64_t regions) {
  const std::uint64_t index_offset = writer.size();
  index.u32(crc32(0, index.bytes()));
  if (auto ok = writer.write(index.bytes()); !ok) {
    return ok;
  }
  LeWriter footer;
  footer.u32(kEndTag);
  footer.u64(regions);
  footer.u64(index_offset);
  footer.u32(crc32(0, footer.bytes()));
  return writer.write(footer.bytes());
}

}  // namespace

Expected<void, Error> saveMap(const VoxelMap& map, const std::string& path) {
  if (auto ok = checkInfoFits(map, path); !ok) {
    return ok;
  }
  const RegionStore& store = map.store();
  const std::vector<LayerSpec> layers = savedLayersOf(store.schema());
  std::vector<int> schema_layers;
  for (const LayerSpec& spec : layers) {
    schema_layers.push_back(store.schema().indexOf(spec.kind));
  }
  const auto raw_bytes = static_cast<std::size_t>(rawRegionBytes(layers, store.voxelsPerRegion()));
  // Regions in coordinate order (z, y, x), so that equal maps give equal files whatever order
  // their regions were created in (and whatever tier they are in: a tiered map streams them
  // through its pool).
  RegionCursor cursor(map);
  auto writer = AtomicFileWriter::open(path);
  if (!writer) {
    return Unexpected(writer.error());
  }
  if (auto ok = writer->write(encodeHeader(map, layers)); !ok) {
    return ok;
  }
  std::vector<std::byte> raw(raw_bytes);
  std::vector<std::byte> packed(::compressBound(static_cast<uLong>(raw_bytes)));
  LeWriter index;
  index.u32(kIndexTag);
  std::uint64_t written = 0;
  while (cursor.next()) {
    const Vec3i coord = cursor.region();
    ++written;
    auto payload =
        packRegion(store, cursor.slot(), coord, layers, schema_layers, raw, packed, path);
    if (!payload) {
      return Unexpected(payload.error());
    }
    index.i32(coord.x);
    index.i32(coord.y);
    index.i32(coord.z);
    index.u64(writer->size());
    if (auto ok = writer->write(blockHeader(coord, raw.size(), *payload).bytes()); !ok) {
      return ok;
    }
    if (auto ok = writer->write(*payload); !ok) {
      return ok;
    }
  }
  if (auto ok = cursor.status(); !ok) {
    return Unexpected(Error{ok.error().code, path + ": " + ok.error().message});
  }
  if (written != cursor.size()) {
    return fail(ErrorCode::kCorrupt, path + ": the map's regions changed while it was saved");
  }
  if (auto ok = writeTrailer(*writer, index, written); !ok) {
    return ok;
  }
  return writer->commit();
}

Result<MapFileHeader> readMapHeader(const std::string& path) {
  auto file = FileReader::open(path);
  if (!file) {
    return Unexpected(file.error());
  }
  auto parsed = readHeader(*file, path);
  if (!parsed) {
    return Unexpected(parsed.error());
  }
  return std::move(parsed->header);
}

Result<VoxelMap> loadMap(const std::string& path, const MapLoadOptions& options) {
  auto file = FileReader::open(path);
  if (!file) {
    return Unexpected(file.error());
  }
  auto parsed = readHeader(*file, path);
  if (!parsed) {
    return Unexpected(parsed.error());
  }
  MapConfig config = parsed->header.config;
  const std::uint64_t per_region =
      config.schema().bytesPerRegion(config.geometry.voxelsPerRegion());
  std::uint64_t capacity = 0;
  if (options.tiers.enabled && options.memory_budget_bytes > 0) {
    // The budget is the pool; regions past it stream through to the cold tiers.
    capacity = std::max<std::uint64_t>(options.memory_budget_bytes / per_region, 1);
    config.tiers = options.tiers;
  } else {
    // Pool: the file's regions, or more when the caller wants room to keep integrating.
    capacity = std::max<std::uint64_t>(
        {parsed->header.region_count, options.memory_budget_bytes / per_region, 1});
  }
  config.memory_budget_bytes = capacity * per_region;
  auto map = VoxelMap::create(config);
  if (!map) {
    return fail(map.error().code, path + ": cannot create the map: " + map.error().message);
  }
  if (auto ok = readRegions(*file, path, *parsed, *map); !ok) {
    return Unexpected(ok.error());
  }
  map->info() = std::move(parsed->header.info);
  return map;
}

}  // namespace raymap::io
