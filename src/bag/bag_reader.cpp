// SPDX-License-Identifier: BSD-3-Clause
// Opening a bag by path: a rosbag2 directory (metadata.yaml names its files, read in turn as one
// bag), or one .mcap / .db3 file.
#include "src/bag/bag_reader.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string_view>

#include <yaml-cpp/yaml.h>

#include "src/bag/mcap_records.hpp"

namespace raymap::bag {
namespace {

namespace fs = std::filesystem;

bool endsWith(const std::string& s, const char* suffix) {
  const std::string_view tail(suffix);
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

/// True when the file at `path` starts with `magic`.
template <std::size_t N>
bool startsWith(const std::string& path, const std::array<std::byte, N>& magic) {
  std::ifstream in(path, std::ios::binary);
  std::array<char, N> head{};
  if (!in.read(head.data(), head.size())) {
    return false;
  }
  return std::equal(head.begin(), head.end(), magic.begin(),
                    [](char a, std::byte b) { return static_cast<std::byte>(a) == b; });
}

/// A zstd frame's magic number (RFC 8878), little-endian 0xFD2FB528.
constexpr std::array<std::byte, 4> kZstdMagic{std::byte{0x28}, std::byte{0xB5}, std::byte{0x2F},
                                              std::byte{0xFD}};

/// rosbag2's file compression (compression_mode: file) names its files BAG.mcap.zstd.
bool isCompressedBagName(const std::string& path) {
  return endsWith(path, ".mcap.zstd") || endsWith(path, ".mcap.zst") ||
         endsWith(path, ".db3.zstd") || endsWith(path, ".db3.zst");
}

/// A file of a bag: .mcap or .db3, or one of those compressed whole (refused when opened).
bool isBagFileName(const std::string& path) {
  return endsWith(path, ".mcap") || endsWith(path, ".db3") || isCompressedBagName(path);
}

Result<std::unique_ptr<BagReader>> openFile(const std::string& path,
                                            const BagReadOptions& options) {
  if (startsWith(path, kZstdMagic)) {
    // Streaming it would still leave the summary at the end out of reach; zstd -d is quick.
    return fail(ErrorCode::kUnsupported,
                path +
                    ": compressed as a whole with zstd (rosbag2's compression_mode: file): "
                    "decompress it first with `zstd -d " +
                    path + "` (then give the decompressed file, or its directory)");
  }
  if (endsWith(path, ".db3")) {
    return openSqliteBag(path);
  }
  return openMcap(path, options);
}

/// The files of a split bag, read one after the other as one bag; topics merged by name.
class MultiFileBag final : public BagReader {
 public:
  MultiFileBag(std::string path, std::vector<std::unique_ptr<BagReader>> files)
      : path_(std::move(path)), files_(std::move(files)) {
    for (const auto& file : files_) {
      std::vector<std::uint32_t> map;
      for (const BagTopic& t : file->topics()) {
        int at = findTopic(topics_, t.name);
        if (at < 0) {
          at = static_cast<int>(topics_.size());
          topics_.push_back(t);
        }
        map.push_back(static_cast<std::uint32_t>(at));
      }
      topic_maps_.push_back(std::move(map));
    }
  }

  const std::string& path() const noexcept override { return path_; }
  const char* storage() const noexcept override { return files_.front()->storage(); }
  const std::vector<BagTopic>& topics() const noexcept override { return topics_; }
  double progress() const noexcept override {
    if (current_ >= files_.size()) {
      return 1.0;
    }
    return (static_cast<double>(current_) + files_[current_]->progress()) /
           static_cast<double>(files_.size());
  }

  const BagPass& pass() const noexcept override { return pass_; }

  std::vector<std::string> openWarnings() const override {
    std::vector<std::string> all;
    for (const auto& file : files_) {
      const std::vector<std::string> some = file->openWarnings();
      all.insert(all.end(), some.begin(), some.end());
    }
    return all;
  }

  Expected<void, Error> rewind() override {
    current_ = 0;
    index_ = 0;
    pass_ = BagPass{};
    return files_.front()->rewind();
  }

  Result<bool> next(BagMessage& out) override {
    while (current_ < files_.size()) {
      auto got = files_[current_]->next(out);
      if (!got) {
        return got;
      }
      if (got.value()) {
        const std::vector<std::uint32_t>& map = topic_maps_[current_];
        out.topic = out.topic < map.size() ? map[out.topic] : out.topic;
        out.index = index_++;
        pass_.messages = index_;
        return true;
      }
      const BagPass& done = files_[current_]->pass();
      pass_.truncated = pass_.truncated || done.truncated;
      pass_.damage.insert(pass_.damage.end(), done.damage.begin(), done.damage.end());
      if (++current_ < files_.size()) {
        if (auto ok = files_[current_]->rewind(); !ok) {
          return Unexpected(ok.error());
        }
      }
    }
    return false;
  }

 private:
  std::string path_;
  std::vector<std::unique_ptr<BagReader>> files_;
  std::vector<BagTopic> topics_;
  std::vector<std::vector<std::uint32_t>> topic_maps_;  // per file: its topic -> ours
  std::size_t current_ = 0;
  std::uint64_t index_ = 0;
  BagPass pass_;
};

/// The files of the bag `dir`, in order: one reader, or one over all of them.
Result<std::unique_ptr<BagReader>> openFiles(const std::string& dir,
                                             const std::vector<std::string>& files,
                                             const BagReadOptions& options) {
  std::vector<std::unique_ptr<BagReader>> readers;
  for (const std::string& f : files) {
    auto r = openFile(f, options);
    if (!r) {
      return Unexpected(r.error());
    }
    readers.push_back(std::move(r).value());
  }
  if (readers.size() == 1) {
    return std::move(readers.front());
  }
  return std::unique_ptr<BagReader>(std::make_unique<MultiFileBag>(dir, std::move(readers)));
}

Result<std::unique_ptr<BagReader>> openDirectory(const std::string& dir,
                                                 const BagReadOptions& options) {
  const std::string metadata = (fs::path(dir) / "metadata.yaml").string();
  std::vector<std::string> files;
  try {
    const YAML::Node root = YAML::LoadFile(metadata);
    const YAML::Node info = root["rosbag2_bagfile_information"];
    if (!info || !info["relative_file_paths"] || !info["relative_file_paths"].IsSequence()) {
      return fail(ErrorCode::kFormat,
                  metadata + ": rosbag2_bagfile_information.relative_file_paths: missing");
    }
    for (const YAML::Node& f : info["relative_file_paths"]) {
      files.push_back((fs::path(dir) / f.as<std::string>()).string());
    }
  } catch (const YAML::Exception& e) {
    return fail(ErrorCode::kFormat, metadata + ": " + e.what());
  }
  if (files.empty()) {
    return fail(ErrorCode::kFormat,
                metadata + ": rosbag2_bagfile_information.relative_file_paths: empty");
  }
  for (const std::string& f : files) {
    if (!fs::exists(f)) {
      return fail(ErrorCode::kIo, metadata + ": relative_file_paths: '" + f + "' does not exist");
    }
  }
  return openFiles(dir, files, options);
}

/// Orders "bag_2.mcap" before "bag_10.mcap": runs of digits compare as numbers.
bool naturalLess(std::string_view a, std::string_view b) {
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  // The run of digits at the start of `s`, taken off it, without leading zeros.
  const auto number = [&](std::string_view& s) {
    std::size_t n = 0;
    while (n < s.size() && digit(s[n])) {
      ++n;
    }
    std::string_view run = s.substr(0, n);
    s.remove_prefix(n);
    while (!run.empty() && run.front() == '0') {
      run.remove_prefix(1);
    }
    return run;
  };
  while (!a.empty() && !b.empty()) {
    if (digit(a.front()) && digit(b.front())) {
      const std::string_view x = number(a);
      const std::string_view y = number(b);
      if (x.size() != y.size() || x != y) {
        return x.size() != y.size() ? x.size() < y.size() : x < y;
      }
      continue;
    }
    if (a.front() != b.front()) {
      return a.front() < b.front();
    }
    a.remove_prefix(1);
    b.remove_prefix(1);
  }
  return a.size() < b.size();
}

/// The bag files directly in `dir`, in rosbag2's split order (bag_0, bag_1, ..., bag_10).
std::vector<std::string> bagFilesIn(const std::string& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file(ec) && isBagFileName(name)) {
      files.push_back(name);
    }
  }
  std::sort(files.begin(), files.end(), naturalLess);
  for (std::string& f : files) {
    f = (fs::path(dir) / f).string();
  }
  return files;
}

/// A directory without metadata.yaml (what `ros2 bag reindex` repairs): its .mcap or .db3
/// files, read in order; MCAP and SQLite files describe their own topics.
Result<std::unique_ptr<BagReader>> openFilesIn(const std::string& dir,
                                               const BagReadOptions& options) {
  const std::vector<std::string> files = bagFilesIn(dir);
  if (files.empty()) {
    return fail(ErrorCode::kFormat, dir +
                                        ": a directory without metadata.yaml and without .mcap "
                                        "or .db3 files is not a bag");
  }
  return openFiles(dir, files, options);
}

}  // namespace

bool isBag(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    return fs::exists(fs::path(path) / "metadata.yaml", ec) || !bagFilesIn(path).empty();
  }
  return isBagFileName(path) || startsWith(path, mcap::kMagic);
}

Result<std::unique_ptr<BagReader>> openBag(const std::string& path, const BagReadOptions& options) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    if (!fs::exists(fs::path(path) / "metadata.yaml", ec)) {
      return openFilesIn(path, options);
    }
    return openDirectory(path, options);
  }
  if (!fs::exists(path, ec)) {
    return fail(ErrorCode::kIo, path + ": no such file or directory");
  }
  return openFile(path, options);
}

Result<BagPass> BagReader::forEach(const Visitor& visit) {
  if (auto ok = rewind(); !ok) {
    return Unexpected(ok.error());
  }
  BagMessage m;
  for (;;) {
    auto got = next(m);
    if (!got) {
      return Unexpected(got.error());
    }
    if (!got.value()) {
      return pass();
    }
    if (!visit(m)) {
      BagPass stopped = pass();
      stopped.stopped = true;
      return stopped;
    }
  }
}

int findTopic(const std::vector<BagTopic>& topics, const std::string& name) noexcept {
  for (std::size_t i = 0; i < topics.size(); ++i) {
    if (topics[i].name == name) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

}  // namespace raymap::bag
