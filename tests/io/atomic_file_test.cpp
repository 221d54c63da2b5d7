// Atomic output files: a destination is the old file or the whole new one, whatever happens during the write
// (a failure, a kill at a controlled point in a child process, another process writing the same path).
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_files.h"

#include "deltagi/error.h"
#include "deltagi/image.h"
#include "io/atomic_file.h"
#include "io/image_output.h"

namespace deltagi {
namespace {

namespace fs = std::filesystem;
using test::readText;
using test::writeText;

class AtomicFileTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("deltagi_atomic_file_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        testing::setBeforeRenameHook(nullptr);
        std::error_code ignored;
        fs::remove_all(dir_, ignored);
    }

    // The temporary files left in the folder.
    std::vector<fs::path> temporaries() const {
        std::vector<fs::path> found;
        for (const auto& entry : fs::directory_iterator(dir_))
            if (entry.path().filename().string().find(".tmp-") != std::string::npos) found.push_back(entry);
        return found;
    }

    fs::path dir_;
};

// Pixels that do not compress away, so that writing the file takes a while (a wide window for the races).
Image noise(int width, int height, uint32_t seed) {
    Image image(width, height, 3);
    uint32_t state = seed * 747796405u + 2891336453u;
    for (float& v : image.data()) {
        state = state * 1664525u + 1013904223u;
        v = static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
    }
    return image;
}

bool samePixels(const Image& a, const Image& b) {
    return a.width() == b.width() && a.height() == b.height() && a.channels() == b.channels() &&
           std::equal(a.data().begin(), a.data().end(), b.data().begin());
}

// The image as a PNG file gives it back (8-bit), by way of `file`. The forked writers below write PNG, not
// EXR: OpenEXR's thread pool, started by an EXR write in this process, does not survive fork().
Image asPng(const Image& image, const fs::path& file) {
    writeImage(image, file);
    return readImage(file);
}

// Runs `child` in a forked process, which exits 0 after it; returns the wait status.
template <typename Child>
int inChildProcess(Child child) {
    const pid_t pid = fork();
    if (pid == 0) {
        child();
        _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    return status;
}

TEST_F(AtomicFileTest, ReplacesTheFileAndLeavesNoTemporary) {
    const fs::path path = dir_ / "figures.json";
    writeText(path, "old\n");
    writeFileAtomically(path, "new\n");
    EXPECT_EQ(readText(path), "new\n");
    EXPECT_TRUE(temporaries().empty());
}

TEST_F(AtomicFileTest, UncommittedFileLeavesTheOldOne) {
    const fs::path path = dir_ / "figures.json";
    writeText(path, "old\n");
    {
        AtomicFile file(path);
        EXPECT_EQ(file.temporaryPath().parent_path(), dir_);
        EXPECT_EQ(file.temporaryPath().extension(), ".json");  // for writers that choose the format by it
        file.write("half of the n");
        EXPECT_EQ(temporaries().size(), 1u);
    }  // e.g. an exception before commit()
    EXPECT_EQ(readText(path), "old\n");
    EXPECT_TRUE(temporaries().empty());
}

TEST_F(AtomicFileTest, KeepsTheReplacedFilesPermissions) {
    const fs::path path = dir_ / "out.png";
    writeImage(Image(4, 4, 3, 0.5f), path);
    fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
    writeImage(Image(4, 4, 3, 0.25f), path);
    EXPECT_EQ(fs::status(path).permissions() & fs::perms::all,
              fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
}

TEST_F(AtomicFileTest, WritingThroughALinkReplacesItsTarget) {
    const fs::path target = dir_ / "target.json", link = dir_ / "link.json";
    writeText(target, "old\n");
    fs::create_symlink(target, link);
    writeFileAtomically(link, "new\n");
    EXPECT_TRUE(fs::is_symlink(link));
    EXPECT_EQ(readText(target), "new\n");
}

// SIGKILL when the new image is complete but not yet renamed: the old image stays, whole.
TEST_F(AtomicFileTest, KillBeforeRenameLeavesTheOldImage) {
    const fs::path path = dir_ / "out.png";
    const Image oldImage = asPng(noise(64, 48, 1), path), newImage = noise(64, 48, 2);
    const int status = inChildProcess([&] {
        testing::setBeforeRenameHook([](const char*) { std::raise(SIGKILL); });
        writeImage(newImage, path);
    });
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "status " << status;
    EXPECT_TRUE(samePixels(readImage(path), oldImage));
    // What a kill cannot clean up: the complete new image, under its temporary name.
    const std::vector<fs::path> left = temporaries();
    ASSERT_EQ(left.size(), 1u);
    EXPECT_TRUE(samePixels(readImage(left[0]), asPng(newImage, dir_ / "expected.png")));
    // The next write of the same file removes it (its process is gone), and leaves alone a temporary of a
    // process that runs (the test's parent), another file's and a name of another pattern.
    const fs::path alive = dir_ / (".out.png.tmp-" + std::to_string(getppid()) + "-0.png");
    const fs::path otherFile = dir_ / (".other.png.tmp-" + left[0].filename().string().substr(13));
    const fs::path notOurs = dir_ / ".out.png.tmp-12x-0.png";
    for (const fs::path& p : {alive, otherFile, notOurs}) std::ofstream(p) << "keep";
    writeImage(newImage, path);
    EXPECT_FALSE(fs::exists(left[0]));
    for (const fs::path& p : {alive, otherFile, notOurs}) EXPECT_TRUE(fs::exists(p)) << p;
}

// SIGTERM at the same point, with a handler like the CLI's: the old file stays and no temporary is left.
TEST_F(AtomicFileTest, TerminateBeforeRenameRemovesTheTemporary) {
    const fs::path path = dir_ / "figures.json";
    writeText(path, "old\n");
    const int status = inChildProcess([&] {
        std::signal(SIGTERM, [](int signal) {
            removeTemporaryOutputs();
            _exit(128 + signal);
        });
        testing::setBeforeRenameHook([](const char*) { std::raise(SIGTERM); });
        writeFileAtomically(path, "new\n");
    });
    ASSERT_TRUE(WIFEXITED(status)) << "status " << status;
    EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM);
    EXPECT_EQ(readText(path), "old\n");
    EXPECT_TRUE(temporaries().empty());
}

// Two processes write the same image over and over while this one reads it: every read finds a whole image
// (the old one or one of the two), and so does the last.
TEST_F(AtomicFileTest, ConcurrentWritersLeaveOneWholeFile) {
    constexpr int kWrites = 8;
    const fs::path path = dir_ / "out.png";
    const Image oldImage = asPng(noise(256, 192, 0), path);
    const std::vector<Image> images{asPng(noise(256, 192, 1), dir_ / "one.png"),
                                    asPng(noise(256, 192, 2), dir_ / "two.png")};
    std::vector<pid_t> writers;
    for (const Image& image : images) {
        const pid_t pid = fork();
        if (pid == 0) {
            for (int i = 0; i < kWrites; ++i) writeImage(image, path);
            _exit(0);
        }
        writers.push_back(pid);
    }
    int reads = 0, broken = 0;
    auto wholeImage = [&](const Image& read) {
        return samePixels(read, oldImage) || samePixels(read, images[0]) || samePixels(read, images[1]);
    };
    for (int running = 2; running > 0;) {
        try {
            ++reads;
            if (!wholeImage(readImage(path))) ++broken;
        } catch (const InputError&) {
            ++broken;
        }
        running = 0;
        for (pid_t pid : writers) running += waitpid(pid, nullptr, WNOHANG) == 0 ? 1 : 0;
    }
    for (pid_t pid : writers) waitpid(pid, nullptr, 0);
    EXPECT_EQ(broken, 0) << "of " << reads << " reads";
    const Image last = readImage(path);
    EXPECT_TRUE(samePixels(last, images[0]) || samePixels(last, images[1]));
    EXPECT_TRUE(temporaries().empty());
}

TEST_F(AtomicFileTest, CheckWritableNamesWhatIsWrong) {
    writeText(dir_ / "file", "");
    try {
        checkWritable(dir_ / "file" / "sub" / "out.png");
        ADD_FAILURE() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("is not a folder"), std::string::npos) << e.what();
    }
    EXPECT_THROW(checkWritable(dir_), InputError);  // a folder, not a file name
    // A folder that does not exist yet is fine where it could be created, and is not created.
    checkWritable(dir_ / "new" / "deeper" / "out.png");
    EXPECT_FALSE(fs::exists(dir_ / "new"));
    EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);  // no probe left
}

// What a signal handler clears: the live temporaries, and the output folders made for them while empty.
TEST_F(AtomicFileTest, RemoveTemporaryOutputsClearsTemporariesAndEmptyFolders) {
    createOutputFolder(dir_ / "aov" / "inner");
    createOutputFolder(dir_ / "kept");
    writeText(dir_ / "kept" / "done.json", "{}\n");
    AtomicFile file(dir_ / "aov" / "inner" / "timings.json");
    file.write("{");
    ASSERT_TRUE(fs::exists(file.temporaryPath()));
    removeTemporaryOutputs();
    EXPECT_FALSE(fs::exists(dir_ / "aov"));
    EXPECT_TRUE(fs::exists(dir_ / "kept" / "done.json"));
}

}  // namespace
}  // namespace deltagi
