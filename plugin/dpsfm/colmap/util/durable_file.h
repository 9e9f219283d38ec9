// Whole-file reads and writes that survive a crash or a power loss: every
// write is fsync'd before it counts, renames are followed by an fsync of the
// folder. The rescaler and the commit transaction write through these only.
//
// POSIX calls rather than std::filesystem / fstream: the standard library
// offers no fsync, and the copy must keep the original's permission bits
// whatever the umask.
#pragma once

#include <filesystem>
#include <string>

namespace dpsfm {

// Whole file; InputError naming the file if it cannot be read.
std::string ReadFileBytes(const std::string& path);

// Creates/truncates `path`, writes `contents`, fsyncs and closes; `mode` are
// the permission bits (set whatever the umask). std::runtime_error naming
// the file on failure.
void WriteFileDurably(const std::string& path,
                      const std::string& contents,
                      unsigned int mode = 0644);

// The suffix of WriteFileAtomically's temporary file.
extern const char kAtomicWriteSuffix[];

// Writes `contents` to `path` atomically: `<path>.tmp`, fsync, rename over
// `path`, fsync of the folder. A reader sees the old file or the new one.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::string& contents);

// Streams `from` to `to` (created or truncated, fsync'd, with from's
// permission bits). InputError if `from` cannot be read, std::runtime_error
// if `to` cannot be written.
void CopyFileDurably(const std::filesystem::path& from,
                     const std::filesystem::path& to);

// fsync of an existing file or folder, so its contents (a folder's: the
// renames and creations in it) survive a power loss. File systems that
// refuse fsync on folders (EINVAL, EROFS) are not an error.
void SyncToDisk(const std::string& path);

// rename(2) / unlink(2) that throw std::runtime_error naming the paths;
// removing a missing file is not an error.
void RenameOrThrow(const std::filesystem::path& from,
                   const std::filesystem::path& to);
void RemoveOrThrow(const std::filesystem::path& path);

// Permission bits of an existing file (0644 if they cannot be read).
unsigned int FileMode(const std::string& path);

}  // namespace dpsfm
