// Output files that are never seen half written: the bytes go to a temporary file in the destination's
// folder, which is flushed to disk and renamed onto the destination only when complete (rename(2) replaces a
// file in one step). A crash, a kill or a failed write leaves the previous file as it was; of two processes
// writing the same path at once, the last rename wins and the file is one of the two, whole.
//
// The temporary files alive in this process, and the folders it created for its outputs, are kept in a
// registry that a signal handler can clear with async-signal-safe calls (removeTemporaryOutputs).
#pragma once

#include <filesystem>
#include <string_view>

namespace deltagi {

class AtomicFile {
  public:
    // Creates the temporary file `.NAME.tmp-<pid>-<counter>EXT` beside `destination` (the destination's
    // extension kept last, for writers that choose the format by it). When the destination exists, the new
    // file takes its permissions; a symbolic link is followed, so the file it points to is replaced. Throws
    // InputError naming the destination when the temporary cannot be created. First removes the temporaries
    // of the same destination that processes which no longer run left behind (a SIGKILL gives no chance to
    // clean up): only that name pattern, only for process ids that kill(pid, 0) finds gone.
    explicit AtomicFile(const std::filesystem::path& destination);
    ~AtomicFile();  // removes the temporary file unless committed
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    // The file to write (by this descriptor, or by name for libraries that open files themselves).
    const std::filesystem::path& temporaryPath() const { return temporary_; }
    const std::filesystem::path& destination() const { return destination_; }
    void write(std::string_view bytes);

    // Flushes the file to disk and closes it; commit() does it when it was not done. Throws InputError.
    void close();
    // Renames the file onto the destination (after close()). Throws InputError on failure (the temporary is
    // removed and the destination left as it was).
    void commit();

  private:
    std::filesystem::path destination_;  // where the file lands (a link's target)
    std::filesystem::path temporary_;
    int fd_ = -1;
    int slot_ = -1;  // in the registry of live temporaries; -1: not registered (registry full)
    bool committed_ = false;
};

// Writes `bytes` to `path` through an AtomicFile.
void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes);

// Throws InputError naming `path` when a file could not be written there: a part of its folder is not a
// folder, or the nearest existing folder does not take a new file (tried by creating and removing one).
// Creates nothing; for checking outputs before a long computation.
void checkWritable(const std::filesystem::path& path);

// Creates `folder` and its missing parents, remembering the ones it created so that
// removeTemporaryOutputs() can take them away again while they are empty. Throws InputError on failure.
void createOutputFolder(const std::filesystem::path& folder);

// Removes this process's live temporary files and the folders createOutputFolder() made that are still
// empty. Async-signal-safe (unlink and rmdir only): for SIGINT/SIGTERM handlers and for failed runs.
void removeTemporaryOutputs() noexcept;

namespace testing {
// Called with the temporary file's path after it is complete and flushed, before the rename: lets a test
// stop the process at that point. nullptr: none.
using BeforeRenameHook = void (*)(const char* temporaryPath);
void setBeforeRenameHook(BeforeRenameHook hook);
}  // namespace testing

}  // namespace deltagi
