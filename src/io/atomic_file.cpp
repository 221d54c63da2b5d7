// Atomic output files: write a temporary beside the destination, fsync, rename
// (src/io/atomic_file.h).
#include "io/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <string>

#include <fmt/format.h>

#include "deltagi/error.h"

namespace fs = std::filesystem;

namespace deltagi {

namespace {

// ---- the registry a signal handler reads ----------------------------------------------------------------
// Fixed slots of plain characters, so that the handler needs no allocation and no lock: a slot is claimed
// (Writing), filled, then published (Live); the handler reads only Live slots.
constexpr int kRegistrySlots = 64;      // more live temporaries/folders than a run ever has at once
constexpr size_t kPathBytes = 4096;     // PATH_MAX on Linux; longer paths are written but not registered
constexpr int kFolderDepthPasses = 16;  // rmdir passes, children before parents

enum SlotState : int { kFree = 0, kWriting = 1, kLive = 2 };

struct Slot {
    std::atomic<int> state{kFree};
    std::array<char, kPathBytes> path{};
};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler reads the slots' state");

std::array<Slot, kRegistrySlots> gTemporaries;
std::array<Slot, kRegistrySlots> gFolders;
std::atomic<testing::BeforeRenameHook> gBeforeRename{nullptr};

// Returns the slot's index, or -1 when the path is too long or every slot is taken.
int registerPath(std::array<Slot, kRegistrySlots>& slots, const std::string& path) {
    if (path.size() >= kPathBytes) return -1;
    for (int i = 0; i < kRegistrySlots; ++i) {
        int expected = kFree;
        if (!slots[i].state.compare_exchange_strong(expected, kWriting)) continue;
        std::memcpy(slots[i].path.data(), path.c_str(), path.size() + 1);
        slots[i].state.store(kLive, std::memory_order_release);
        return i;
    }
    return -1;
}

void unregisterPath(std::array<Slot, kRegistrySlots>& slots, int index) {
    if (index >= 0) slots[index].state.store(kFree, std::memory_order_release);
}

std::string errnoText(int error) {
    return std::strerror(error);
}

// The nearest folder of `path` that exists ("." for a relative path with none); throws when a part that
// exists is not a folder.
fs::path nearestExistingFolder(const fs::path& path, const fs::path& shown) {
    fs::path folder = path.parent_path();
    for (;;) {
        const fs::path probe = folder.empty() ? fs::path(".") : folder;
        std::error_code error;
        const fs::file_status status = fs::status(probe, error);
        if (fs::exists(status)) {
            if (!fs::is_directory(status))
                throw InputError(shown.string(),
                                 fmt::format("cannot write here: '{}' is not a folder", probe.string()));
            return probe;
        }
        if (folder.empty() || folder == folder.root_path()) return probe;  // reported by the probe file
        folder = folder.parent_path();
    }
}

// Removes the temporary files `.NAME.tmp-<pid>-<n>EXT` of `destination` left beside it by processes that no
// longer run (killed with SIGKILL, or by a power cut, before they could clean up): only this exact pattern,
// and only where kill(pid, 0) says there is no such process on this machine. Errors are ignored: a leftover
// that stays is harmless.
void removeLeftoverTemporaries(const fs::path& destination) {
    const std::string prefix = "." + destination.filename().string() + ".tmp-";
    const std::string extension = destination.extension().string();
    const fs::path folder = destination.parent_path().empty() ? fs::path(".") : destination.parent_path();
    std::error_code error;
    for (fs::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
        const std::string name = it->path().filename().string();
        if (name.size() <= prefix.size() + extension.size() || name.compare(0, prefix.size(), prefix) != 0 ||
            name.compare(name.size() - extension.size(), extension.size(), extension) != 0)
            continue;
        // <pid>-<n> between the prefix and the extension, digits only.
        const std::string middle = name.substr(prefix.size(), name.size() - prefix.size() - extension.size());
        const size_t dash = middle.find('-');
        if (dash == 0 || dash == std::string::npos || dash + 1 == middle.size() ||
            middle.find_first_not_of("0123456789-") != std::string::npos ||
            middle.find('-', dash + 1) != std::string::npos)
            continue;
        const std::string pidText = middle.substr(0, dash);
        if (pidText.size() > 9) continue;
        const pid_t pid = static_cast<pid_t>(std::stol(pidText));
        if (pid <= 0 || pid == getpid()) continue;
        if (::kill(pid, 0) == 0 || errno != ESRCH) continue;  // alive, or not ours to know
        std::error_code ignored;
        if (fs::is_regular_file(it->symlink_status(ignored))) fs::remove(it->path(), ignored);
    }
}

// Writing through a symbolic link replaces the file it points to, as an in-place write would.
fs::path resolveLink(const fs::path& path) {
    std::error_code error;
    if (!fs::is_symlink(path, error)) return path;
    fs::path target = fs::weakly_canonical(path, error);
    return error ? path : target;
}

}  // namespace

// ---- AtomicFile ------------------------------------------------------------------------------------------

AtomicFile::AtomicFile(const fs::path& destination) : destination_(resolveLink(destination)) {
    static std::atomic<unsigned> counter{0};
    const fs::path folder = destination_.parent_path();
    const std::string name = destination_.filename().string();
    const std::string extension = destination_.extension().string();
    removeLeftoverTemporaries(destination_);
    constexpr int kAttempts = 100;  // names taken by leftovers of killed processes with the same pid
    int error = EEXIST;
    for (int attempt = 0; attempt < kAttempts && fd_ < 0; ++attempt) {
        temporary_ = folder / fmt::format(".{}.tmp-{}-{}{}", name, getpid(), counter++, extension);
        // Registered before it exists, so that no signal finds it created but unknown.
        slot_ = registerPath(gTemporaries, temporary_.string());
        fd_ = ::open(temporary_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd_ >= 0) break;
        error = errno;
        unregisterPath(gTemporaries, slot_);
        slot_ = -1;
        if (error != EEXIST) break;
    }
    if (fd_ < 0) throw InputError(destination.string(), "cannot write file: " + errnoText(error));
}

AtomicFile::~AtomicFile() {
    if (fd_ >= 0) ::close(fd_);
    if (!committed_) ::unlink(temporary_.c_str());
    unregisterPath(gTemporaries, slot_);
}

void AtomicFile::write(std::string_view bytes) {
    while (!bytes.empty()) {
        const ssize_t written = ::write(fd_, bytes.data(), bytes.size());
        if (written < 0 && errno == EINTR) continue;
        if (written <= 0)
            throw InputError(destination_.string(),
                             "cannot write file: " + errnoText(written < 0 ? errno : EIO));
        bytes.remove_prefix(static_cast<size_t>(written));
    }
}

void AtomicFile::close() {
    if (fd_ < 0) return;
    auto fail = [&](const char* what) {
        throw InputError(destination_.string(),
                         fmt::format("cannot write file ({}): {}", what, errnoText(errno)));
    };
    if (::fsync(fd_) != 0) fail("fsync");
    // The replaced file's permissions (set now: a read-only mode would stop writers that open by name).
    struct stat old {};
    if (::stat(destination_.c_str(), &old) == 0 && S_ISREG(old.st_mode)) ::fchmod(fd_, old.st_mode & 07777);
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail("close");
}

void AtomicFile::commit() {
    close();
    if (auto hook = gBeforeRename.load()) hook(temporary_.c_str());
    if (::rename(temporary_.c_str(), destination_.c_str()) != 0)
        throw InputError(destination_.string(), "cannot write file (rename): " + errnoText(errno));
    committed_ = true;
    unregisterPath(gTemporaries, slot_);
    slot_ = -1;
    // The rename itself reaches the disk with the folder.
    const fs::path folder = destination_.parent_path().empty() ? fs::path(".") : destination_.parent_path();
    const int folderFd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (folderFd >= 0) {
        ::fsync(folderFd);
        ::close(folderFd);
    }
}

void writeFileAtomically(const fs::path& path, std::string_view bytes) {
    AtomicFile file(path);
    file.write(bytes);
    file.commit();
}

// ---- checks and folders ----------------------------------------------------------------------------------

void checkWritable(const fs::path& path) {
    std::error_code error;
    if (fs::is_directory(path, error)) throw InputError(path.string(), "is a folder, expected a file name");
    // The temporary beside it, `.NAME.tmp-<pid>-<n>EXT`, must fit a file name too (255 bytes on Linux): a
    // name that leaves no room fails here, not after the work.
    constexpr size_t kTemporaryExtra = 40;
    const long nameMax = ::pathconf(nearestExistingFolder(path, path).c_str(), _PC_NAME_MAX);
    const size_t limit = nameMax > 0 ? static_cast<size_t>(nameMax) : 255;
    const size_t length =
        path.filename().string().size() + path.extension().string().size() + kTemporaryExtra;
    if (length > limit)
        throw InputError(
            path.string(),
            fmt::format("the file name is {} bytes; with its temporary's part the longest this file "
                        "system takes is {} bytes: choose a shorter name",
                        path.filename().string().size(),
                        limit - kTemporaryExtra - path.extension().string().size()));
    const fs::path folder = nearestExistingFolder(path, path);
    static std::atomic<unsigned> counter{0};
    const fs::path probe = folder / fmt::format(".deltagi-probe-{}-{}", getpid(), counter++);
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0)
        throw InputError(path.string(),
                         fmt::format("cannot write in folder '{}': {}", folder.string(), errnoText(errno)));
    ::close(fd);
    ::unlink(probe.c_str());
}

void createOutputFolder(const fs::path& folder) {
    if (folder.empty()) return;
    nearestExistingFolder(folder / "x", folder);  // a part that is a file is named as such
    // Parents first, each one this call creates registered for removal while empty.
    fs::path partial;
    for (const fs::path& part : folder) {
        partial /= part;
        std::error_code error;
        if (fs::is_directory(partial, error)) continue;
        if (!fs::create_directory(partial, error) && error)
            throw InputError(folder.string(), "cannot create folder: " + error.message());
        if (!error) registerPath(gFolders, partial.string());
    }
}

void removeTemporaryOutputs() noexcept {
    for (Slot& slot : gTemporaries)
        if (slot.state.load(std::memory_order_acquire) == kLive) ::unlink(slot.path.data());
    // A folder empties when its children go: repeat until a pass removes nothing.
    for (int pass = 0; pass < kFolderDepthPasses; ++pass) {
        bool removed = false;
        for (Slot& slot : gFolders) {
            if (slot.state.load(std::memory_order_acquire) != kLive || ::rmdir(slot.path.data()) != 0)
                continue;
            slot.state.store(kFree, std::memory_order_release);
            removed = true;
        }
        if (!removed) break;
    }
}

namespace testing {
void setBeforeRenameHook(BeforeRenameHook hook) {
    gBeforeRename.store(hook);
}
}  // namespace testing

}  // namespace deltagi
