// SPDX-License-Identifier: BSD-3-Clause
// Which compressor the cold tiers use (docs/large-maps.md): every region of a map file, as the
// tiers hold it (all layers as byte planes), compressed and decompressed with LZ4, zstd at fast
// levels and zlib at level 1. Prints one JSON line per codec: ratio and MB/s of raw region bytes.
//   raymap-tier-codecs MAP.rmap [REPEATS]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include <lz4.h>
#include <zlib.h>
#include <zstd.h>

#include "src/io/map_file.hpp"
#include "src/map/region_planes.hpp"
#include "tools/raymap/json_output.hpp"

namespace {

using Bytes = std::vector<char>;
using Clock = std::chrono::steady_clock;

struct Codec {
  const char* name;
  std::function<std::size_t(const Bytes&, Bytes&)> compress;  // returns packed size
  std::function<bool(const char*, std::size_t, Bytes&)> decompress;
};

double seconds(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Every region as the tiers hold it: the layers' byte planes one after the other.
std::vector<Bytes> regionPlanes(const raymap::VoxelMap& map) {
  const raymap::RegionStore& store = map.store();
  const std::uint32_t voxels = store.voxelsPerRegion();
  std::vector<Bytes> regions;
  store.forEachRegion([&](std::uint32_t slot, raymap::Vec3i) {
    Bytes planes;
    for (int l = 0; l < store.schema().size(); ++l) {
      const std::size_t at = planes.size();
      planes.resize(at + store.layerRegionBytes(l));
      raymap::encodeBytePlanes(store.layerBytes(slot, l), voxels,
                               store.schema().at(l).bytes_per_voxel / 4u,
                               reinterpret_cast<std::byte*>(planes.data() + at));
    }
    regions.push_back(std::move(planes));
  });
  return regions;
}

/// LZ4, zstd at levels 1, 3 and -5, and zlib at level 1.
std::vector<Codec> codecsToCompare() {
  const auto zstd_codec = [](int level) {
    return Codec{nullptr,
                 [level](const Bytes& in, Bytes& out) {
                   out.resize(ZSTD_compressBound(in.size()));
                   return ZSTD_compress(out.data(), out.size(), in.data(), in.size(), level);
                 },
                 [](const char* in, std::size_t n, Bytes& out) {
                   return ZSTD_decompress(out.data(), out.size(), in, n) == out.size();
                 }};
  };
  std::vector<Codec> codecs;
  codecs.push_back(Codec{
      "lz4",
      [](const Bytes& in, Bytes& out) {
        out.resize(static_cast<std::size_t>(LZ4_compressBound(static_cast<int>(in.size()))));
        return static_cast<std::size_t>(LZ4_compress_default(
            in.data(), out.data(), static_cast<int>(in.size()), static_cast<int>(out.size())));
      },
      [](const char* in, std::size_t n, Bytes& out) {
        return LZ4_decompress_safe(in, out.data(), static_cast<int>(n),
                                   static_cast<int>(out.size())) == static_cast<int>(out.size());
      }});
  for (const auto& [name, level] :
       {std::pair{"zstd-1", 1}, std::pair{"zstd-3", 3}, std::pair{"zstd--5", -5}}) {
    Codec c = zstd_codec(level);
    c.name = name;
    codecs.push_back(c);
  }
  codecs.push_back(Codec{
      "zlib-1",
      [](const Bytes& in, Bytes& out) {
        uLongf n = compressBound(static_cast<uLong>(in.size()));
        out.resize(n);
        compress2(reinterpret_cast<Bytef*>(out.data()), &n,
                  reinterpret_cast<const Bytef*>(in.data()), static_cast<uLong>(in.size()), 1);
        return static_cast<std::size_t>(n);
      },
      [](const char* in, std::size_t n, Bytes& out) {
        uLongf size = static_cast<uLongf>(out.size());
        return uncompress(reinterpret_cast<Bytef*>(out.data()), &size,
                          reinterpret_cast<const Bytef*>(in), static_cast<uLong>(n)) == Z_OK &&
               size == out.size();
      }});
  return codecs;
}

/// Compresses and decompresses every region `repeats` times with `c` and prints its JSON line
/// (medians). False when a region does not round-trip.
bool measureCodec(const Codec& c, const std::vector<Bytes>& regions, int repeats) {
  std::uint64_t raw = 0;
  for (const Bytes& r : regions) {
    raw += r.size();
  }
  std::vector<double> compress_s;
  std::vector<double> decompress_s;
  std::uint64_t packed = 0;
  for (int rep = 0; rep < repeats; ++rep) {
    std::vector<Bytes> out(regions.size());
    packed = 0;
    Clock::time_point start = Clock::now();
    for (std::size_t i = 0; i < regions.size(); ++i) {
      const std::size_t n = c.compress(regions[i], out[i]);
      out[i].resize(n);
      packed += n;
    }
    compress_s.push_back(seconds(start));
    Bytes back;
    start = Clock::now();
    for (std::size_t i = 0; i < regions.size(); ++i) {
      back.resize(regions[i].size());
      if (!c.decompress(out[i].data(), out[i].size(), back) || back != regions[i]) {
        std::fprintf(stderr, "raymap-tier-codecs: %s did not round-trip\n", c.name);
        return false;
      }
    }
    decompress_s.push_back(seconds(start));
  }
  std::sort(compress_s.begin(), compress_s.end());
  std::sort(decompress_s.begin(), decompress_s.end());
  const double mb = static_cast<double>(raw) / 1e6;
  const raymap::cli::Json line = {
      {"codec", c.name},
      {"regions", regions.size()},
      {"raw_bytes", raw},
      {"packed_bytes", packed},
      {"ratio", static_cast<double>(raw) / static_cast<double>(std::max<std::uint64_t>(packed, 1))},
      {"compress_mb_s", mb / compress_s[compress_s.size() / 2]},
      {"decompress_mb_s", mb / decompress_s[decompress_s.size() / 2]},
  };
  std::printf("%s\n", raymap::cli::dumpJson(line, raymap::cli::JsonStyle::kCompact).c_str());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: raymap-tier-codecs MAP.rmap [REPEATS]\n");
    return 2;
  }
  const int repeats = argc > 2 ? std::max(1, std::atoi(argv[2])) : 3;
  auto map = raymap::io::loadMap(argv[1]);
  if (!map) {
    std::fprintf(stderr, "raymap-tier-codecs: %s\n", map.error().message.c_str());
    return 1;
  }
  const std::vector<Bytes> regions = regionPlanes(*map);
  for (const Codec& c : codecsToCompare()) {
    if (!measureCodec(c, regions, repeats)) {
      return 1;
    }
  }
  return 0;
}
