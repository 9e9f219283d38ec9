// Reading ahead: the prefetcher hands out exactly the views a plain loop of
// LoadView would, in the same order, at every depth; it never holds more than
// `depth` views ahead of the one Next() returned last, and never reads beyond
// the order it was given; a read's time is its own, and prefetching hides it
// from Next(); a read's error reaches the caller at that view (not earlier,
// not lost); dropping the prefetcher waits for the reads in flight.
//
// WorkspaceReader::LoadView is not virtual, so the reads are real ones. To
// make a read last a known time, and to see which reads have started, the
// tests hold views at a gate: a Linux write lease on the view's left frame,
// which LoadView opens first. Opening a file under a write lease blocks until
// the holder releases it (within one process too), and the holder sees the
// attempt (F_GETLEASE reports the break).
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "dpsfm/colmap/io/view_prefetcher.h"
#include "dpsfm/colmap/io/workspace.h"
#include "dpsfm/colmap/io/workspace_reader.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Read::seconds and Read::waited come from COLMAP's Timer, the test measures
// with the steady clock: comparisons between the two allow this much.
constexpr double kClockSlack = 0.005;
// How long a test waits for something that must happen (a read starting).
constexpr double kTimeout = 20;

std::string LeftFrame(const TempDir& dir, int view) {
  return dir / ("dp/left/v" + std::to_string(view) + ".png");
}

// A sparse model of `n` images v<i>.png whose DP frames are flat at grey
// level 10 (i + 1), each with one triangulated point at depth 2 + i; image
// `broken` (if >= 0) has an unreadable right frame.
void WriteModel(const TempDir& dir, int n, int broken) {
  const std::string model = dir / "sparse";
  std::filesystem::create_directories(model);
  colmap::Reconstruction reconstruction;
  AddCamera(&reconstruction,
            colmap::Camera::CreateFromModelName(1, "PINHOLE", 40, 40, 30));
  for (int i = 0; i < n; ++i) {
    colmap::Image image;
    image.SetImageId(i + 1);
    image.SetName("v" + std::to_string(i) + ".png");
    image.SetCameraId(1);
    image.SetPoints2D({Eigen::Vector2d(20.5, 15.5)});
    AddRegisteredImage(&reconstruction, image, colmap::Rigid3d());
    colmap::Track track;
    track.AddElement(i + 1, 0);
    reconstruction.AddPoint3D(
        Eigen::Vector3d(0, 0, 2.0 + i), track, Eigen::Vector3ub(0, 0, 0));
  }
  reconstruction.WriteBinary(model);
  for (const char* side : {"left", "right"}) {
    std::filesystem::create_directories(dir / (std::string("dp/") + side));
    for (int i = 0; i < n; ++i) {
      const std::string path =
          dir / (std::string("dp/") + side + "/v" + std::to_string(i) + ".png");
      if (i == broken && std::string(side) == "right") {
        WriteTextFile(path, "not a PNG");
      } else {
        cv::imwrite(path, cv::Mat(30, 40, CV_8UC1, cv::Scalar(10 * (i + 1))));
      }
    }
  }
}

// The workspace WriteModel(dir, n, broken) writes, opened as a run would.
WorkspaceReader ReaderFor(const TempDir& dir, int n, int broken) {
  WriteModel(dir, n, broken);
  ScaleRunOptions options;
  options.input_path = dir / "sparse";
  options.dp_image_path = dir / "dp";
  options.focal_length_mm = 50;
  options.f_number = 2;
  return WorkspaceReader(options, ResolveWorkspaceLayout(options));
}

// Gates on the reads of chosen views (see the top of the file). A watcher
// thread notes when each gated read starts (its open of the left frame
// blocks) and releases the gate `hold` seconds later, so that read lasts at
// least `hold`. Create the gates after every other read of those files
// (WorkspaceReader's constructor, LoadView for expected values), and before
// the prefetcher, so that they outlive its reads.
class ReadGates {
 public:
  ReadGates(const TempDir& dir, const std::map<int, double>& hold_by_view) {
    // A lease break signals the holder with SIGIO, fatal by default.
    previous_sigio_ = std::signal(SIGIO, SIG_IGN);
    for (const auto& [view, hold] : hold_by_view) {
      Gate& gate = gates_[view];
      gate.hold = std::chrono::duration_cast<Clock::duration>(
          std::chrono::duration<double>(hold));
      const std::string path = LeftFrame(dir, view);
      gate.fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
      if (gate.fd < 0 || fcntl(gate.fd, F_SETLEASE, F_WRLCK) != 0) {
        error_ += "cannot take a write lease on " + path + "; ";
      }
    }
    watcher_ = std::thread([this] { Watch(); });
  }
  ~ReadGates() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    changed_.notify_all();
    watcher_.join();
    std::signal(SIGIO, previous_sigio_);
  }

  // Empty if every gate is in place.
  const std::string& error() const { return error_; }

  // The gated views whose reads have started.
  std::set<int> Started() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::set<int> started;
    for (const auto& [view, gate] : gates_) {
      if (gate.started) started.insert(view);
    }
    return started;
  }
  bool Released(int view) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return gates_.at(view).released;
  }
  // When the watcher saw the read start (no earlier than it did).
  Clock::time_point StartTime(int view) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return gates_.at(view).start;
  }
  // False if it did not happen within kTimeout seconds.
  bool WaitStarted(int view) { return WaitFor(view, &Gate::started); }
  bool WaitReleased(int view) { return WaitFor(view, &Gate::released); }

 private:
  struct Gate {
    Clock::duration hold{};
    int fd = -1;
    bool started = false;
    bool released = false;
    Clock::time_point start;
  };

  bool WaitFor(int view, bool Gate::*flag) {
    std::unique_lock<std::mutex> lock(mutex_);
    const Gate& gate = gates_.at(view);
    return changed_.wait_for(lock,
                             std::chrono::duration<double>(kTimeout),
                             [&] { return gate.*flag; });
  }

  static void Release(Gate* gate) {
    if (gate->fd >= 0) {
      fcntl(gate->fd, F_SETLEASE, F_UNLCK);
      close(gate->fd);
      gate->fd = -1;
    }
    gate->released = true;
  }

  void Watch() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!stop_) {
      bool changed = false;
      for (auto& [view, gate] : gates_) {
        if (gate.released || gate.fd < 0) continue;
        // During a break the lease reads as what it is being downgraded to.
        if (!gate.started && fcntl(gate.fd, F_GETLEASE) != F_WRLCK) {
          gate.started = true;
          gate.start = Clock::now();  // after the read began to wait
          changed = true;
        }
        if (gate.started && Clock::now() >= gate.start + gate.hold) {
          Release(&gate);
          changed = true;
        }
      }
      if (changed) changed_.notify_all();
      changed_.wait_for(lock, std::chrono::milliseconds(1));
    }
    for (auto& [view, gate] : gates_) Release(&gate);
    changed_.notify_all();
  }

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::map<int, Gate> gates_;
  bool stop_ = false;
  std::string error_;
  void (*previous_sigio_)(int) = SIG_DFL;
  std::thread watcher_;
};

std::set<int> FirstOf(const std::vector<int>& order, size_t count) {
  return std::set<int>(order.begin(),
                       order.begin() + std::min(count, order.size()));
}

TEST(ViewPrefetcher, SameViewsInTheSameOrderAtEveryDepth) {
  TempDir dir;
  const WorkspaceReader reader = ReaderFor(dir, 6, -1);
  const std::vector<int> order = {4, 0, 5, 2};  // not all views
  std::map<int, DPView> expected;
  for (const int index : order) expected[index] = reader.LoadView(index);
  // The frames tell the views apart.
  ASSERT_NE(cv::norm(expected[4].left, expected[0].left, cv::NORM_INF), 0);
  for (const int depth : {0, 1, 2, 5}) {
    const Clock::time_point created = Clock::now();
    ViewPrefetcher prefetcher(&reader, order, depth, FrameReduction{});
    for (const int index : order) {
      const Clock::time_point called = Clock::now();
      const ViewPrefetcher::Read read = prefetcher.Next();
      const double call_seconds = SecondsSince(called);
      const double since_created = SecondsSince(created);
      const DPView& want = expected[index];
      EXPECT_EQ(read.view.name, "v" + std::to_string(index) + ".png") << depth;
      ASSERT_EQ(read.view.left.size(), want.left.size());
      ASSERT_EQ(read.view.right.size(), want.right.size());
      EXPECT_EQ(cv::norm(read.view.left, want.left, cv::NORM_INF), 0) << depth;
      EXPECT_EQ(cv::norm(read.view.right, want.right, cv::NORM_INF), 0)
          << depth;
      ASSERT_EQ(read.view.depth_points.size(), 1u);
      EXPECT_NEAR(read.view.depth_points[0].depth, 2.0 + index, 1e-9);
      // A read takes time (more than the timer's microsecond), and no more
      // than has passed since the prefetcher could start it; Next() blocks
      // no longer than the call lasted (a view read ahead can take it at
      // once: 0 us).
      EXPECT_GT(read.seconds, 0) << depth;
      EXPECT_LE(read.seconds, since_created + kClockSlack) << depth;
      EXPECT_LE(read.waited, call_seconds + kClockSlack) << depth;
      // Without prefetching the read happens inside Next().
      if (depth == 0) EXPECT_GE(read.waited, read.seconds);
    }
    // Only the given order is read.
    EXPECT_THROW(prefetcher.Next(), std::out_of_range) << depth;
  }
  EXPECT_THROW(ViewPrefetcher(&reader, order, -1, FrameReduction{}),
               std::invalid_argument);
}

TEST(ViewPrefetcher, ReadsAtMostDepthViewsAhead) {
  TempDir dir;
  const WorkspaceReader reader = ReaderFor(dir, 7, -1);
  const std::vector<int> order = {6, 1, 4, 0, 3};  // 2 and 5 are not read
  // Time for reads that must not happen to show up if they did.
  const auto settle = std::chrono::milliseconds(50);
  for (const int depth : {0, 1, 2, 3}) {
    std::map<int, double> no_hold;
    for (int view = 0; view < 7; ++view) no_hold[view] = 0;
    ReadGates gates(dir, no_hold);
    ASSERT_EQ(gates.error(), "");
    ViewPrefetcher prefetcher(&reader, order, depth, FrameReduction{});
    // Before the first Next(): the first `depth` views, read ahead.
    for (int k = 0; k < depth; ++k) {
      EXPECT_TRUE(gates.WaitStarted(order[k])) << depth << " " << k;
    }
    std::this_thread::sleep_for(settle);
    EXPECT_EQ(gates.Started(), FirstOf(order, static_cast<size_t>(depth)))
        << "depth " << depth;
    for (size_t k = 0; k < order.size(); ++k) {
      EXPECT_EQ(prefetcher.Next().view.name,
                "v" + std::to_string(order[k]) + ".png");
      // Next() for view k has let the read of view k + depth begin.
      if (depth > 0 && k + depth < order.size()) {
        EXPECT_TRUE(gates.WaitStarted(order[k + depth])) << depth << " " << k;
      }
      std::this_thread::sleep_for(settle);
      const std::set<int> started = gates.Started();
      EXPECT_EQ(started, FirstOf(order, k + 1 + depth))
          << "depth " << depth << " after view " << k;
      EXPECT_LE(started.size(), k + 1 + static_cast<size_t>(depth))
          << "views held ahead of the last one handed out";
    }
    EXPECT_THROW(prefetcher.Next(), std::out_of_range) << depth;
    EXPECT_EQ(gates.Started(), FirstOf(order, order.size()));
  }
}

// Next(false) starts no read (a checkpoint that may end the run follows
// the view); Resume() starts those held back, up to `depth` ahead.
TEST(ViewPrefetcher, ReadsHeldBackUntilResumed) {
  TempDir dir;
  const WorkspaceReader reader = ReaderFor(dir, 5, -1);
  const std::vector<int> order = {3, 0, 4, 1};
  const auto settle = std::chrono::milliseconds(50);
  for (const int depth : {1, 2}) {
    std::map<int, double> no_hold;
    for (int view = 0; view < 5; ++view) no_hold[view] = 0;
    ReadGates gates(dir, no_hold);
    ASSERT_EQ(gates.error(), "");
    ViewPrefetcher prefetcher(&reader, order, depth, FrameReduction{});
    EXPECT_EQ(prefetcher.Next(false).view.name, "v3.png");
    std::this_thread::sleep_for(settle);
    // Only the reads started before: the first `depth` views.
    EXPECT_EQ(gates.Started(), FirstOf(order, static_cast<size_t>(depth)))
        << "depth " << depth;
    prefetcher.Resume();
    EXPECT_TRUE(gates.WaitStarted(order[depth])) << depth;
    std::this_thread::sleep_for(settle);
    EXPECT_EQ(gates.Started(), FirstOf(order, depth + 1u)) << depth;
    // Held back again, then read on by the next Next().
    EXPECT_EQ(prefetcher.Next(false).view.name, "v0.png");
    std::this_thread::sleep_for(settle);
    EXPECT_EQ(gates.Started(), FirstOf(order, depth + 1u)) << depth;
    // Without Resume(), Next() starts what it needs.
    EXPECT_EQ(prefetcher.Next().view.name, "v4.png");
    EXPECT_EQ(prefetcher.Next().view.name, "v1.png");
    EXPECT_EQ(gates.Started(), FirstOf(order, order.size()));
    EXPECT_THROW(prefetcher.Next(), std::out_of_range) << depth;
  }
}

TEST(ViewPrefetcher, ReadTimesAreTheReadsAndPrefetchHidesThem) {
  TempDir dir;
  const WorkspaceReader reader = ReaderFor(dir, 3, -1);
  const double hold = 0.3;  // each gated read lasts at least this long
  {
    // Depth 0: the read happens inside Next(), which waits all of it.
    ReadGates gates(dir, {{1, hold}});
    ASSERT_EQ(gates.error(), "");
    ViewPrefetcher prefetcher(&reader, {0, 1}, 0, FrameReduction{});
    EXPECT_EQ(prefetcher.Next().view.name, "v0.png");
    const ViewPrefetcher::Read read = prefetcher.Next();
    EXPECT_EQ(read.view.name, "v1.png");
    EXPECT_GE(read.seconds, hold - kClockSlack);
    EXPECT_LT(read.seconds, hold + kTimeout);
    EXPECT_GE(read.waited, read.seconds);
  }
  {
    ReadGates gates(dir, {{1, hold}, {2, hold}});
    ASSERT_EQ(gates.error(), "");
    ViewPrefetcher prefetcher(&reader, {0, 1, 2}, 1, FrameReduction{});
    EXPECT_EQ(prefetcher.Next().view.name, "v0.png");
    // View 1 is read while the caller works on view 0: once its gate has
    // opened (the read has lasted `hold`), Next() waits at most for the
    // rest of it, a small part of the read.
    ASSERT_TRUE(gates.WaitReleased(1));
    ViewPrefetcher::Read read = prefetcher.Next();
    EXPECT_EQ(read.view.name, "v1.png");
    EXPECT_GE(read.seconds, hold - kClockSlack);
    EXPECT_LT(read.waited, read.seconds);
    EXPECT_LT(read.waited, hold / 2);
    // View 2 is asked for while its read is held: Next() waits until the
    // gate opens, and no longer than the read itself took.
    ASSERT_TRUE(gates.WaitStarted(2));
    const Clock::time_point called = Clock::now();
    read = prefetcher.Next();
    EXPECT_EQ(read.view.name, "v2.png");
    const double held_before_call =
        std::chrono::duration<double>(called - gates.StartTime(2)).count();
    EXPECT_GE(read.seconds, hold - kClockSlack);
    EXPECT_GE(read.waited, hold - held_before_call - kClockSlack);
    EXPECT_LE(read.waited, read.seconds + 0.1);
  }
}

TEST(ViewPrefetcher, ReadErrorSurfacesAtItsView) {
  TempDir dir;
  const WorkspaceReader reader = ReaderFor(dir, 5, 3);
  const auto expect_error_names_v3 = [](ViewPrefetcher* prefetcher, int depth) {
    try {
      prefetcher->Next();
      ADD_FAILURE() << "the broken view was read at depth " << depth;
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find("v3"), std::string::npos)
          << error.what();
    }
  };
  for (const int depth : {0, 1, 3}) {
    ReadGates gates(dir, {{3, 0}});
    ASSERT_EQ(gates.error(), "");
    ViewPrefetcher prefetcher(
        &reader, {0, 1, 2, 3, 4}, depth, FrameReduction{});
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(prefetcher.Next().view.name, "v" + std::to_string(k) + ".png")
          << depth;
      // At depth 3 the broken view's read starts at the first Next() and
      // fails while views 1 and 2 are still to be handed out.
      if (depth == 3 && k == 0) {
        EXPECT_TRUE(gates.WaitStarted(3));
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    }
    expect_error_names_v3(&prefetcher, depth);
  }
  // The broken view first: read ahead in the constructor, which does not
  // throw; the error comes with the first Next().
  for (const int depth : {0, 2}) {
    ReadGates gates(dir, {{3, 0}});
    ASSERT_EQ(gates.error(), "");
    std::unique_ptr<ViewPrefetcher> prefetcher;
    EXPECT_NO_THROW(
        prefetcher = std::make_unique<ViewPrefetcher>(
            &reader, std::vector<int>{3, 0}, depth, FrameReduction{}));
    ASSERT_NE(prefetcher, nullptr);
    if (depth > 0) EXPECT_TRUE(gates.WaitStarted(3));
    expect_error_names_v3(prefetcher.get(), depth);
  }
}

// Each frame of each view is reduced once, during its read and on the
// reading thread (the caller's own at depth 0), before Next() hands the
// view out with the size the frames had; what the reduction throws reaches
// the caller at that view, as a read's error does.
TEST(ViewPrefetcher, EachFrameIsReducedOnTheReadingThread) {
  TempDir dir;
  const WorkspaceReader reader = ReaderFor(dir, 5, -1);
  // The views' frames are flat, each at its own level: v3's tells it apart.
  const float v3_level = reader.LoadView(3).left.at<float>(0, 0);
  ASSERT_NE(reader.LoadView(2).left.at<float>(0, 0), v3_level);
  for (const int depth : {0, 1, 3}) {
    std::mutex mutex;
    std::map<float, std::vector<std::thread::id>> reduced;
    const auto reduce = [&](const cv::Mat& frame, const cv::Size&) {
      const float level = frame.at<float>(0, 0);
      {
        std::lock_guard<std::mutex> lock(mutex);
        reduced[level].push_back(std::this_thread::get_id());
      }
      if (level == v3_level) throw InputError("cannot reduce v3");
      return cv::Mat(frame(cv::Rect(0, 0, 2, 1)).clone());
    };
    ViewPrefetcher prefetcher(
        &reader, {4, 0, 3, 1}, depth, FrameReduction{reduce});
    for (const int index : {4, 0}) {
      const ViewPrefetcher::Read read = prefetcher.Next();
      EXPECT_EQ(read.view.name, "v" + std::to_string(index) + ".png");
      EXPECT_EQ(read.view.left.size(), cv::Size(2, 1)) << depth;
      EXPECT_EQ(read.view.right.size(), cv::Size(2, 1)) << depth;
      EXPECT_EQ(read.view.frame_size, cv::Size(40, 30)) << depth;
    }
    try {
      prefetcher.Next();
      ADD_FAILURE() << "v3's reduction did not fail at depth " << depth;
    } catch (const InputError& error) {
      EXPECT_EQ(std::string(error.what()), "cannot reduce v3");
    }
    EXPECT_EQ(prefetcher.Next().view.name, "v1.png");
    std::lock_guard<std::mutex> lock(mutex);
    // Four views, both frames of each at the same level; v3 stopped at its
    // left frame.
    EXPECT_EQ(reduced.size(), 4u) << depth;
    for (const auto& [level, threads] : reduced) {
      ASSERT_EQ(threads.size(), level == v3_level ? 1u : 2u)
          << level << " at depth " << depth;
      for (const std::thread::id& thread : threads) {
        if (depth == 0) {
          EXPECT_EQ(thread, std::this_thread::get_id()) << level;
        } else {
          EXPECT_NE(thread, std::this_thread::get_id()) << level;
        }
      }
    }
  }
}

// A view Next() returned belongs to its caller alone: nothing in the
// prefetcher (or COLMAP's thread pool, which keeps its finished tasks until
// Wait()) holds its frames or depth map, so a run holds at most depth + 1
// views whatever its length.
TEST(ViewPrefetcher, ReturnedViewsAreHeldByTheCallerAlone) {
  TempDir dir;
  const WorkspaceReader reader = ReaderFor(dir, 4, -1);
  for (const int depth : {0, 1, 3}) {
    ViewPrefetcher prefetcher(&reader, {0, 1, 2, 3}, depth, FrameReduction{});
    for (int k = 0; k < 4; ++k) {
      const ViewPrefetcher::Read read = prefetcher.Next();
      for (const cv::Mat* mat :
           {&read.view.left, &read.view.right, &read.view.depth}) {
        if (mat->empty()) continue;
        ASSERT_NE(mat->u, nullptr);
        EXPECT_EQ(mat->u->refcount, 1) << "depth " << depth << ", view " << k;
      }
    }
  }
}

TEST(ViewPrefetcher, DroppingWaitsForTheReadsInFlight) {
  TempDir dir;
  const WorkspaceReader reader = ReaderFor(dir, 5, -1);
  const double hold = 0.1;
  ReadGates gates(dir, {{0, hold}, {1, hold}, {2, hold}, {3, hold}, {4, 0}});
  ASSERT_EQ(gates.error(), "");
  {
    // Dropped at once: reads 0-3 are in flight (or queued), 4 is not.
    ViewPrefetcher dropped(&reader, {0, 1, 2, 3, 4}, 4, FrameReduction{});
  }
  // Every read in flight ran to its end (its gate opened before its open
  // returned), none beyond them started.
  for (int view = 0; view < 4; ++view) {
    EXPECT_TRUE(gates.Released(view)) << "read of v" << view;
  }
  EXPECT_EQ(gates.Started(), (std::set<int>{0, 1, 2, 3}));
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
