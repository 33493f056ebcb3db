// SPDX-License-Identifier: BSD-3-Clause
#include "tests/support/same_map.hpp"

#include <vector>

#include "raymap/mapper.hpp"
#include <gtest/gtest.h>

#include "src/io/map_file.hpp"
#include "tests/device/device_map_compare.hpp"

namespace raymap::test {

void expectSameMap(const std::string& cli, const std::string& library) {
  auto a = io::loadMap(cli);
  ASSERT_TRUE(a) << a.error().message;
  auto b = io::loadMap(library);
  ASSERT_TRUE(b) << b.error().message;
  EXPECT_EQ(a->config().schema().size(), b->config().schema().size());
  // The parameters the file records (the layers alone may not show a small difference).
  const MapConfig& x = a->config();
  const MapConfig& y = b->config();
  EXPECT_EQ(a->mode(), b->mode());
  EXPECT_EQ(x.semantics, y.semantics);
  EXPECT_EQ(x.geometry.resolution, y.geometry.resolution);
  EXPECT_EQ(x.geometry.region_voxels, y.geometry.region_voxels);
  EXPECT_EQ(x.voxel_mean, y.voxel_mean);
  EXPECT_EQ(x.decay_rate, y.decay_rate);
  EXPECT_EQ(x.occupancy_layer, y.occupancy_layer);
  EXPECT_EQ(x.occupancy.hit, y.occupancy.hit);
  EXPECT_EQ(x.occupancy.miss, y.occupancy.miss);
  EXPECT_EQ(x.occupancy.clamp_min, y.occupancy.clamp_min);
  EXPECT_EQ(x.occupancy.clamp_max, y.occupancy.clamp_max);
  EXPECT_EQ(x.occupancy.threshold, y.occupancy.threshold);
  EXPECT_EQ(x.ndt.sensor_noise, y.ndt.sensor_noise);
  EXPECT_EQ(x.ndt.regulariser, y.ndt.regulariser);
  EXPECT_EQ(x.ndt.sample_threshold, y.ndt.sample_threshold);
  EXPECT_EQ(x.ndt.reinit_probability, y.ndt.reinit_probability);
  EXPECT_EQ(x.ndt.reinit_count, y.ndt.reinit_count);
  EXPECT_EQ(x.ndt.adaptation_rate, y.ndt.adaptation_rate);
  EXPECT_EQ(x.ndt.initial_intensity_variance, y.ndt.initial_intensity_variance);
  EXPECT_EQ(x.tsdf.truncation_m, y.tsdf.truncation_m);
  EXPECT_EQ(x.tsdf.max_weight, y.tsdf.max_weight);
  EXPECT_EQ(x.tsdf.dropoff_m, y.tsdf.dropoff_m);
  EXPECT_GT(a->summarise().regions, 0u);
  EXPECT_EQ(a->summarise().regions, b->summarise().regions);
  EXPECT_EQ(differingRegions(*a, *b), 0u);
}

void mapWithLibrary(const std::string& input, const RecordingOptions& read,
                    const MapperConfig& config, const std::string& out, LibraryRun* run,
                    ReadAs read_as) {
  auto mapper = Mapper::create(config);
  ASSERT_TRUE(mapper) << mapper.error().message;
  auto reader = RecordingReader::open(input, read);
  ASSERT_TRUE(reader) << reader.error().message;
  std::vector<WorldRay> scan;
  RecordedCloud cloud;
  for (;;) {
    auto more = read_as == ReadAs::kScans ? reader->nextScan(scan) : reader->nextCloud(cloud);
    ASSERT_TRUE(more) << more.error().message;
    if (!*more) {
      break;
    }
    if (read_as == ReadAs::kScans) {
      ASSERT_TRUE(mapper->integrate(scan));
    } else {
      ASSERT_FALSE(cloud.sensor_poses.empty());
      auto integrated = mapper->integrate(cloud.points, cloud.sensor_poses);
      ASSERT_TRUE(integrated) << integrated.error().message;
    }
  }
  auto saved = mapper->save(out);
  ASSERT_TRUE(saved) << saved.error().message;
  if (run != nullptr) {
    run->report = reader->report();
    run->bag = reader->isBag();
  }
}

}  // namespace raymap::test
