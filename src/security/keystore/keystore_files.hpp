// SPDX-License-Identifier: BSD-3-Clause
// All-or-nothing file output for the keystore writer: files and links written under temporary
// names and renamed into place together, folders removed again when a call fails.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "raymap/error.hpp"
#include <sys/types.h>

namespace raymap::security {

/// Modes of the files written (the umask still applies, as for any new file).
inline constexpr mode_t kPrivateFileMode = 0600;
inline constexpr mode_t kPublicFileMode = 0644;
inline constexpr mode_t kPrivateFolderMode = 0700;
inline constexpr mode_t kFolderMode = 0777;

/// @brief Files and symbolic links that appear together or not at all: each is written beside
/// its path under a hidden temporary name (".NAME.tmp-XXXXXXXX") with its final mode from the
/// start, and commit() renames them into place in the order they were added. What is not
/// committed is removed by the destructor. Move-only.
class FileBatch {
 public:
  FileBatch() = default;
  ~FileBatch();
  FileBatch(const FileBatch&) = delete;
  FileBatch& operator=(const FileBatch&) = delete;
  FileBatch(FileBatch&&) noexcept = default;
  FileBatch& operator=(FileBatch&&) noexcept = delete;

  /// @brief Writes `content` to a temporary file beside `target`, created with `mode`.
  /// @return an error naming `target` and the reason
  Result<void> addFile(const std::filesystem::path& target, std::string_view content, mode_t mode);
  /// @brief Makes a temporary symbolic link beside `target` pointing at `link_to` (as written).
  Result<void> addLink(const std::filesystem::path& target, const std::filesystem::path& link_to);
  /// @brief Renames every temporary onto its path (replacing what is there), in order.
  /// @return an error naming the file that could not be renamed; the rest are removed, and so
  /// are the files this batch had already renamed into paths where nothing was before
  Result<void> commit();
  /// @brief The paths of the files and links, in the order added.
  std::vector<std::filesystem::path> targets() const;

 private:
  struct Entry {
    std::filesystem::path temporary;
    std::filesystem::path target;
    bool new_path = false;  ///< nothing was at `target` when the entry was added
  };
  std::vector<Entry> entries_;
};

/// @brief Folders this call created, removed again (if still empty, deepest first) by the
/// destructor unless keep() was called. Not copyable.
class CreatedFolders {
 public:
  CreatedFolders() = default;
  ~CreatedFolders();
  CreatedFolders(const CreatedFolders&) = delete;
  CreatedFolders& operator=(const CreatedFolders&) = delete;

  /// @brief Creates `folder` (with `mode`) and its missing parents (with kFolderMode),
  /// remembering each one it created; an existing folder is fine.
  /// @return an error naming the folder that could not be created
  Result<void> create(const std::filesystem::path& folder, mode_t mode = kFolderMode);
  /// @brief The call succeeded: the folders stay.
  void keep() noexcept { created_.clear(); }

 private:
  std::vector<std::filesystem::path> created_;
};

/// @brief Whether `path` exists as anything (a dangling link counts).
bool pathExists(const std::filesystem::path& path);

}  // namespace raymap::security
