#include "dpsfm/colmap/io/view_prefetcher.h"

#include <memory>
#include <stdexcept>
#include <utility>

#include "colmap/util/threading.h"
#include "colmap/util/timer.h"

namespace dpsfm {
namespace {

ViewPrefetcher::Read TimedRead(const WorkspaceReader* reader,
                               int index,
                               const FrameReduction& reduction,
                               bool decode_together) {
  colmap::Timer timer;
  timer.Start();
  ViewPrefetcher::Read read;
  try {
    read.view = reader->LoadView(index, reduction, decode_together);
  } catch (...) {
    read.error = std::current_exception();
  }
  read.seconds = timer.ElapsedSeconds();
  return read;
}

}  // namespace

ViewPrefetcher::ViewPrefetcher(const WorkspaceReader* reader,
                               std::vector<int> order,
                               int depth,
                               FrameReduction reduction,
                               bool decode_together)
    : reader_(reader),
      order_(std::move(order)),
      reduction_(std::move(reduction)),
      depth_(depth),
      decode_together_(decode_together) {
  if (depth_ < 0) {
    throw std::invalid_argument("prefetch depth must be >= 0");
  }
  if (depth_ > 0) {
    pool_ = std::make_unique<colmap::ThreadPool>(depth_);
    Resume();
  }
}

ViewPrefetcher::~ViewPrefetcher() {
  for (std::future<Read>& read : in_flight_) {
    if (read.valid()) read.wait();
  }
}

void ViewPrefetcher::Launch() {
  const int index = order_[launched_++];
  const WorkspaceReader* reader = reader_;
  const FrameReduction* reduction = &reduction_;
  const bool together = decode_together_;
  auto promise = std::make_shared<std::promise<Read>>();
  in_flight_.push_back(promise->get_future());
  pool_->AddTask([reader, index, reduction, together, promise]() {
    promise->set_value(TimedRead(reader, index, *reduction, together));
  });
}

ViewPrefetcher::Read ViewPrefetcher::Next(bool read_on) {
  colmap::Timer timer;
  timer.Start();
  Read read;
  if (depth_ == 0) {
    if (launched_ >= order_.size()) {
      throw std::out_of_range("no more views to read");
    }
    read =
        TimedRead(reader_, order_[launched_++], reduction_, decode_together_);
  } else {
    // Reads held back by Next(false) without Resume() start now.
    if (in_flight_.empty() && launched_ < order_.size()) Launch();
    if (in_flight_.empty()) throw std::out_of_range("no more views to read");
    std::future<Read> next = std::move(in_flight_.front());
    in_flight_.pop_front();
    read = next.get();  // moves the view out
    // The next read starts once this one is out, so reads stay in order
    // and at most depth views wait in memory.
    if (read_on) Resume();
  }
  if (read.error) std::rethrow_exception(read.error);
  read.waited = timer.ElapsedSeconds();
  return read;
}

void ViewPrefetcher::Resume() {
  while (static_cast<int>(in_flight_.size()) < depth_ &&
         launched_ < order_.size()) {
    Launch();
  }
}

}  // namespace dpsfm
