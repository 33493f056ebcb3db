// SPDX-License-Identifier: BSD-3-Clause
// The command line's view of library messages: configuration keys shown as the flags its user
// typed (tools/raymap/option_names.hpp).
#include <set>
#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include "tools/raymap/option_names.hpp"

namespace raymap::cli {
namespace {

TEST(OptionNames, AKeyAloneBecomesItsFlag) {
  EXPECT_EQ(withCliFlags("raise the memory budget (map.max_memory)"),
            "raise the memory budget (--max-memory)");
  EXPECT_EQ(withCliFlags("bag.invalid_as_free needs bag.max_range (the length of the free rays)"),
            "--invalid-as-free needs --max-range (the length of the free rays)");
  EXPECT_EQ(withCliFlags("several topics: choose with bag.pose_topic."),
            "several topics: choose with --pose-topic.");
  EXPECT_EQ(withCliFlags("map.spill_dir"), "--spill-dir");
}

TEST(OptionNames, AKeyWithANumberBecomesTheFlagAndTheNumber) {
  EXPECT_EQ(withCliFlags("heightmap.size: 500: larger than the rolling window (51.2 m)"),
            "--size 500: larger than the rolling window (51.2 m)");
  EXPECT_EQ(withCliFlags("heightmap.centre: -5,0.5,1e+03: outside the map"),
            "--center -5,0.5,1e+03: outside the map");
  EXPECT_EQ(withCliFlags("heightmap.min_clearance: nan: must be >= 0 metres"),
            "--min-clearance nan: must be >= 0 metres");
  EXPECT_EQ(withCliFlags("heightmap.floor_depth: -inf: must be >= 0"),
            "--floor -inf: must be >= 0");
  EXPECT_EQ(withCliFlags("backend.cuda_device: 7: no such CUDA device"),
            "--cuda-device 7: no such CUDA device");
  EXPECT_EQ(withCliFlags("heightmap.size: .5"), "--size .5");
}

// The replay library's warnings and errors (src/replay) read as they did when raymap replay and
// raymap record wrote them.
TEST(OptionNames, ReplayAndRecordMessagesNameTheirFlags) {
  EXPECT_EQ(withCliFlags("replay.rate: max: no progress report on rt/diagnostics (is raymapd "
                         "running?): publishing unpaced"),
            "--rate max: no progress report on rt/diagnostics (is raymapd running?): publishing "
            "unpaced");
  EXPECT_EQ(withCliFlags("replay.skip_damaged: bag.mcap: 2 chunks skipped"),
            "--skip-damaged: bag.mcap: 2 chunks skipped");
  EXPECT_EQ(withCliFlags("is not replayed (replay.include_outputs replays it)"),
            "is not replayed (--include-outputs replays it)");
  EXPECT_EQ(withCliFlags("record.compression applies to record.format: mcap (a .rmlog is raw "
                         "capture)"),
            "--compression applies to --format mcap (a .rmlog is raw capture)");
  EXPECT_EQ(withCliFlags("record.compression: 'brotli' is not none, zstd or lz4"),
            "--compression: 'brotli' is not none, zstd or lz4");
}

TEST(OptionNames, AKeyWithOneOfItsValuesBecomesTheFlagAndTheValue) {
  EXPECT_EQ(withCliFlags("backend.name: cuda: no device (backend.fallback: cpu maps on the CPU "
                         "instead)"),
            "--backend cuda: no device (--fallback cpu maps on the CPU instead)");
  EXPECT_EQ(withCliFlags("bag.pose_source: auto: poses from /tf; bag.pose_source: tf takes /tf"),
            "--pose-source auto: poses from /tf; --pose-source tf takes /tf");
  EXPECT_EQ(withCliFlags("use backend.device_planning: host"), "use --device-planning host");
  EXPECT_EQ(withCliFlags("the region cache (backend.gpu_memory: cache)"),
            "the region cache (--gpu-memory cache)");
  EXPECT_EQ(withCliFlags("use export.mode: ndt-points"), "use --mode ndt-points");
  EXPECT_EQ(withCliFlags("a map built with map.mode: decay or map.decay_rate: true"),
            "a map built with populate --mode decay or --decay-rate");
}

TEST(OptionNames, AKeyWithAValueThatIsAFlagOfItsOwnBecomesThatFlag) {
  EXPECT_EQ(withCliFlags("raise the memory budget (map.max_memory), or turn the tiers off "
                         "(map.tiers: false)"),
            "raise the memory budget (--max-memory), or turn the tiers off (--no-tiers)");
}

TEST(OptionNames, AKeyFollowedByProseKeepsItsColon) {
  EXPECT_EQ(withCliFlags("heightmap.centre: must be three finite numbers (metres)"),
            "--center: must be three finite numbers (metres)");
  EXPECT_EQ(withCliFlags("bag.topic: /data/run.mcap has no topic '/points'"),
            "--topic: /data/run.mcap has no topic '/points'");
  // A word that is not one of the key's values is prose, not the flag's value.
  EXPECT_EQ(withCliFlags("backend.name: unknown backend 'quantum'"),
            "--backend: unknown backend 'quantum'");
  EXPECT_EQ(withCliFlags("backend.fallback: cpus"), "--fallback: cpus");
}

TEST(OptionNames, OnlyWholeKeysAreReplaced) {
  // Inside a longer key, a longer word or a path, and keys the table does not hold: unchanged.
  for (const std::string_view text :
       {"heightmap.sizes", "xheightmap.size", "heightmap.size_m", "heightmap.size.x",
        "/maps/heightmap.size", "raymapd.heightmap.size", "heightmap.mode: fill",
        "queues.max_latency_s: 2", "map.tiers", "map.tiers: true", "sensors[0].max_range",
        "a-heightmap.size"}) {
    EXPECT_EQ(withCliFlags(text), text);
  }
  // "map.mode" is not the end of "heightmap.mode".
  EXPECT_EQ(withCliFlags("heightmap.mode: fill, map.mode: tsdf"),
            "heightmap.mode: fill, populate --mode tsdf");
}

TEST(OptionNames, TextWithoutKeysIsUnchanged) {
  for (const std::string_view text :
       {"", "map.rmap: not a raymap map file", "--size 5: already a flag", "a: b: c", ".", ":"}) {
    EXPECT_EQ(withCliFlags(text), text);
  }
}

TEST(OptionNames, TheTableHasEachKeyOnceInSectionFieldForm) {
  std::set<std::string_view> keys;
  for (const OptionFlag& row : optionFlags()) {
    EXPECT_TRUE(keys.insert(row.key).second) << row.key << " twice";
    const std::string_view key = row.key.substr(0, row.key.find(':'));
    const std::size_t dot = key.find('.');
    ASSERT_NE(dot, std::string_view::npos) << row.key;
    EXPECT_GT(dot, 0u) << row.key;
    EXPECT_EQ(key.find_first_not_of("abcdefghijklmnopqrstuvwxyz_."), std::string_view::npos)
        << row.key;
    EXPECT_NE(row.flag.find("--"), std::string_view::npos) << row.key;
    // Every row renders itself.
    EXPECT_EQ(withCliFlags(row.key), row.flag) << row.key;
  }
}

// A configuration file's error names the file's own key (raymap populate --config): it stays a
// key, while the same key in a library message becomes the flag.
TEST(OptionNames, AKeyAfterAFilesLineStaysTheFilesKey) {
  EXPECT_EQ(withCliFlags("robot.yaml: line 3: map.semantics: must be ray or scan"),
            "robot.yaml: line 3: map.semantics: must be ray or scan");
  EXPECT_EQ(withCliFlags("map options: map.semantics: ray is needed"),
            "map options: --semantics ray is needed");
}

}  // namespace
}  // namespace raymap::cli
