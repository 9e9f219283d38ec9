// Reading views ahead of the blur search: decoding the DP frames and reading
// (and resampling) the depth map of the next views overlaps with the current
// view's AddView, so on a long run the reads cost only what they do not hide.
#pragma once

#include <deque>
#include <exception>
#include <future>
#include <memory>
#include <vector>

#include "dpsfm/colmap/io/workspace_reader.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace colmap {
class ThreadPool;
}  // namespace colmap

namespace dpsfm {

class ViewPrefetcher {
 public:
  // Reads reader->LoadView(order[k], reduction) for k = 0, 1, ... in that
  // order on `depth` worker threads (so the reduction, e.g. DPScaleEstimator::
  // ReduceFrame, runs there too), at most `depth` views ahead of the one
  // Next() returned last (so memory holds at most depth + 1 views). depth 0
  // reads in Next() itself. The reader and whatever the reduction uses must
  // outlive the prefetcher. With `decode_together` each view's two frame
  // files are decoded at once (WorkspaceReader::LoadView), so that a read
  // the search waits for takes both cores.
  ViewPrefetcher(const WorkspaceReader* reader,
                 std::vector<int> order,
                 int depth,
                 FrameReduction reduction,
                 bool decode_together = false);
  // Waits for the reads in flight (their views are dropped).
  ~ViewPrefetcher();

  struct Read {
    DPView view;
    double seconds = 0;  // the read itself
    double waited = 0;   // how long Next() blocked for it
    // The read's error, rethrown by Next(). Tasks never throw: COLMAP 4's
    // thread pool treats an exception no one collected through Wait() as
    // fatal when it is destroyed.
    std::exception_ptr error;
  };
  // The next view in order; rethrows its read's error (InputError). With
  // `read_on` false no further read starts until Resume(): a checkpoint that
  // may end the run follows this view, and a view read for nothing would be
  // held, with its read's buffers, through the checkpoint's estimate, the
  // run's peak (about 120 MB at 3000 x 2000: the file's bytes, the frame as
  // decoded, the reduced views and the depth map; heaptrack).
  Read Next(bool read_on = true);
  // Starts the reads Next(false) held back.
  void Resume();

 private:
  void Launch();

  const WorkspaceReader* reader_;
  const std::vector<int> order_;
  const FrameReduction reduction_;
  const int depth_;
  const bool decode_together_;
  size_t launched_ = 0;
  std::unique_ptr<colmap::ThreadPool> pool_;
  // The reads in flight. Each task fills a promise and returns nothing:
  // COLMAP 4's ThreadPool keeps every finished task until Wait(), and a Read
  // returned through it (two frames and a depth map, 200 MB at 3000 x 2000)
  // would stay for the whole run. Next() moves the value out of its future,
  // so what the pool keeps of the promise is empty.
  std::deque<std::future<Read>> in_flight_;
};

}  // namespace dpsfm
