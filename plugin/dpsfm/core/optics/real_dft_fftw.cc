// RealDft's transforms on FFTW's single-precision plans (built with
// -DDPSFM_WITH_FFTW=ON; FFTW is GPL-2.0-or-later, README "Licence"). At the
// searches' sizes (48-144 px) cv::dft, the default backend
// (real_dft_opencv.cc), takes 2-3x their time (docs/benchmark.md). The
// plans are made with FFTW_ESTIMATE: a transform's arithmetic then depends
// on its size and nothing else (FFTW_MEASURE's choice depends on timings),
// so answers are the same run to run and at any thread count.
//
// A 2-D transform is done in two passes, rows then columns (forward) and
// columns then rows (inverse), so that rows known to be zero are not
// transformed and rows not needed are not computed back (what cv::dft's
// nonzero_rows does). The column pass runs between the spectrum and a
// per-thread work array, or into contiguous columns there, where FFTW
// computes the same bits that way as in place (checked per size when the
// plans are made), because it then needs no buffers.
#include "dpsfm/core/optics/real_dft.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <new>
#include <utility>
#include <vector>

#include <fftw3.h>

#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace {

// FFTW's planner is not thread-safe (its execute functions are): every plan
// is made under this lock.
std::mutex& PlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

// Plans made on scratch arrays from fftwf_malloc run on any arrays of the
// same alignment (FFTW's new-array execute); cv::Mat's allocations are
// aligned at least as well (cv::fastMalloc), and views into them are
// refused here rather than run with the wrong alignment.
void CheckAligned(const void* data, const char* what) {
  DPSFM_INVARIANT(fftwf_alignment_of(
                  const_cast<float*>(static_cast<const float*>(data))) == 0)
      << "RealDft: the " << what << " is not aligned for FFTW";
}

// The calling thread's work array of at least `count` complex numbers,
// aligned as FFTW allocates (the column passes between two arrays): kept
// for the thread, grown when a larger transform needs it.
fftwf_complex* ThreadWork(size_t count) {
  struct Work {
    ~Work() { fftwf_free(data); }
    fftwf_complex* data = nullptr;
    size_t count = 0;
  };
  thread_local Work work;
  if (work.count < count) {
    fftwf_free(work.data);
    work.data = fftwf_alloc_complex(count);
    if (work.data == nullptr) throw std::bad_alloc();
    work.count = count;
  }
  return work.data;
}

}  // namespace

struct RealDft::Plans {
  Plans(int rows, int cols)
      : rows(rows),
        cols(cols),
        half(cols / 2 + 1),
        column_dist(BufferDist(rows)) {
    forward_rows = std::make_unique<std::atomic<fftwf_plan>[]>(rows + 1);
    inverse_rows = std::make_unique<std::atomic<fftwf_plan>[]>(rows + 1);
    for (int k = 0; k <= rows; ++k) {
      forward_rows[k].store(nullptr);
      inverse_rows[k].store(nullptr);
    }
    fftwf_complex* spectrum = fftwf_alloc_complex(rows * half);
    fftwf_complex* work = fftwf_alloc_complex(rows * half);
    fftwf_complex* columns = fftwf_alloc_complex(half * column_dist);
    forward = MakeColumnPass(FFTW_FORWARD, spectrum, work, columns);
    inverse = MakeColumnPass(FFTW_BACKWARD, spectrum, work, columns);
    fftwf_free(columns);
    fftwf_free(work);
    fftwf_free(spectrum);
  }

  // The column pass, `half` columns `rows` long and `half` apart, from `in`
  // into `out` (the same array: in place), their elements `out_stride`
  // apart and the columns `out_dist` (`half` and 1 as in `in`, or 1 and
  // `column_dist`: contiguous columns), planned with FFTW_ESTIMATE and
  // `flags`.
  fftwf_plan Columns(int sign,
                     fftwf_complex* in,
                     fftwf_complex* out,
                     int out_stride,
                     int out_dist,
                     unsigned flags) {
    return fftwf_plan_many_dft(1,
                               &rows,
                               half,
                               in,
                               nullptr,
                               half,
                               1,
                               out,
                               nullptr,
                               out_stride,
                               out_dist,
                               sign,
                               FFTW_ESTIMATE | flags);
  }

  // The column pass in place, and the fastest way found to compute its bits
  // without its buffers. FFTW_ESTIMATE plans the in-place pass over strided
  // columns either as a loop of single strided columns or through a buffer
  // ("dft-buffered": the columns transformed into a buffer of contiguous
  // columns, then copied back by fftwf_cpy2d, the largest single function
  // in a profile of the six make-cost scenes). Two other ways, tried in
  // turn:
  // - between the spectrum and a work array (`apart`): FFTW needs no
  //   buffers then, 3.4x faster at 40 px, 2.7x at 60, 2.3x at 96, 1.5-1.6x
  //   at 36 and 45, the same at 64 (docs/benchmark.md); at 48,
  //   50, 54, 72, 80 and 100 px it picks other codelets, whose rounding
  //   differs;
  // - into contiguous columns (`to_columns`), the buffered plan's own first
  //   step planned alone, then the rows wanted gathered from them
  //   (GatherRows): the same codelets, without FFTW's copy back through its
  //   tiles, and the inverse gathers only the rows it keeps; 1.6x at 48 px,
  //   1.1x at 72 and 80.
  // Whether each computes the in-place plan's bits is decided here, on a
  // pseudo-random probe, on the machine that runs them: the plans depend on
  // its SIMD, so a table of sizes could not say, and an answer must not
  // depend on which pass ran. The in-place plan runs where neither does.
  struct ColumnPlans {
    fftwf_plan in_place = nullptr;
    fftwf_plan apart = nullptr;
    fftwf_plan to_columns = nullptr;
  };
  ColumnPlans MakeColumnPass(int sign,
                             fftwf_complex* spectrum,
                             fftwf_complex* work,
                             fftwf_complex* columns) {
    ColumnPlans pass;
    pass.in_place = Columns(sign, spectrum, spectrum, half, 1, 0);
    DPSFM_INVARIANT(pass.in_place != nullptr)
        << "FFTW made no plan for " << cols << "x" << rows;
    const size_t floats = 2 * static_cast<size_t>(rows) * half;
    std::vector<float> probe(floats);
    uint32_t state = 12345;
    for (float& v : probe) {
      state = state * 1664525u + 1013904223u;  // Numerical Recipes' LCG
      v = static_cast<float>(state >> 8) * (1.0f / 16777216.0f) - 0.5f;
    }
    float* s = reinterpret_cast<float*>(spectrum);
    std::copy(probe.begin(), probe.end(), s);
    fftwf_execute_dft(pass.in_place, spectrum, spectrum);
    const std::vector<float> expected(s, s + floats);
    auto same = [&](const fftwf_complex* result) {
      return std::memcmp(result, expected.data(), sizeof(float) * floats) == 0;
    };
    pass.apart = Columns(sign, spectrum, work, half, 1, FFTW_DESTROY_INPUT);
    if (pass.apart != nullptr) {
      std::copy(probe.begin(), probe.end(), s);
      fftwf_execute_dft(pass.apart, spectrum, work);
      if (same(work)) return pass;
      fftwf_destroy_plan(pass.apart);
      pass.apart = nullptr;
    }
    pass.to_columns = Columns(sign, spectrum, columns, 1, column_dist, 0);
    if (pass.to_columns != nullptr) {
      std::copy(probe.begin(), probe.end(), s);
      fftwf_execute_dft(pass.to_columns, spectrum, columns);
      GatherRows(columns, cv::Range(0, rows), work);
      if (same(work)) return pass;
      fftwf_destroy_plan(pass.to_columns);
      pass.to_columns = nullptr;
    }
    return pass;
  }

  // Rows `range` of the column pass's result, from its contiguous columns
  // (Columns) into `out`, rows.size() x half. Column by column: reads in
  // order, writes `half` apart, all in the first-level cache at these sizes.
  void GatherRows(const fftwf_complex* columns,
                  const cv::Range& range,
                  fftwf_complex* out) const {
    const int count = range.size();
    for (int u = 0; u < half; ++u) {
      const fftwf_complex* column =
          columns + static_cast<size_t>(u) * column_dist + range.start;
      fftwf_complex* to = out + u;
      for (int y = 0; y < count; ++y) {
        std::memcpy(to[static_cast<size_t>(y) * half],
                    column[y],
                    sizeof(fftwf_complex));
      }
    }
  }

  // FFTW's spacing of buffered vectors (kernel/buffered.c, X(bufdist)): the
  // least n' >= n with n' = 6 (mod 8). The buffered plan's first step is
  // planned for that spacing, and another may get other codelets.
  static int BufferDist(int n) { return n + ((6 - n) % 8 + 8) % 8; }

  // A thread's work array: the rows (the spectrum's layout) and, after them
  // at FFTW's alignment, the contiguous columns when the pass uses them.
  fftwf_complex* Work(fftwf_complex** columns) const {
    const size_t rows_part = (static_cast<size_t>(rows) * half + 7) / 8 * 8;
    fftwf_complex* work =
        ThreadWork(rows_part + static_cast<size_t>(half) * column_dist);
    *columns = work + rows_part;
    return work;
  }

  // The plan of `count` rows (real <-> half spectrum), made on first use.
  fftwf_plan Rows(bool forward, int count) const {
    std::atomic<fftwf_plan>& slot =
        forward ? forward_rows[count] : inverse_rows[count];
    fftwf_plan plan = slot.load(std::memory_order_acquire);
    if (plan != nullptr) return plan;
    std::lock_guard<std::mutex> lock(PlannerMutex());
    plan = slot.load(std::memory_order_relaxed);
    if (plan != nullptr) return plan;
    float* image = fftwf_alloc_real(count * cols);
    fftwf_complex* spectrum = fftwf_alloc_complex(count * half);
    int n = cols;
    plan = forward ? fftwf_plan_many_dft_r2c(1, &n, count, image, nullptr, 1,
                                             cols, spectrum, nullptr, 1, half,
                                             FFTW_ESTIMATE)
                   : fftwf_plan_many_dft_c2r(1, &n, count, spectrum, nullptr,
                                             1, half, image, nullptr, 1, cols,
                                             FFTW_ESTIMATE);
    fftwf_free(image);
    fftwf_free(spectrum);
    DPSFM_INVARIANT(plan != nullptr)
        << "FFTW made no plan for " << count << " rows of " << cols;
    slot.store(plan, std::memory_order_release);
    return plan;
  }

  int rows, cols, half;
  // The spacing of contiguous columns (Columns).
  int column_dist;
  ColumnPlans forward, inverse;
  std::unique_ptr<std::atomic<fftwf_plan>[]> forward_rows, inverse_rows;
};

const RealDft::Plans* RealDft::PlansFor(const cv::Size& size) {
  // Kept for the process: a handful of sizes, each a few plans.
  static std::map<std::pair<int, int>, std::unique_ptr<Plans>> registry;
  std::lock_guard<std::mutex> lock(PlannerMutex());
  std::unique_ptr<Plans>& plans = registry[{size.height, size.width}];
  if (plans == nullptr) {
    plans = std::make_unique<Plans>(size.height, size.width);
  }
  return plans.get();
}

RealDft::ColumnPass RealDft::ColumnPassOf(bool forward) const {
  const Plans::ColumnPlans& pass = forward ? plans_->forward : plans_->inverse;
  if (pass.apart != nullptr) return ColumnPass::kApart;
  if (pass.to_columns != nullptr) return ColumnPass::kThroughColumns;
  return ColumnPass::kInPlace;
}

void RealDft::ForwardTransform(const cv::Mat& image,
                               int nonzero_rows,
                               cv::Mat* spectrum) const {
  CheckAligned(image.data, "image");
  CheckAligned(spectrum->data, "spectrum");
  auto* out = reinterpret_cast<fftwf_complex*>(spectrum->ptr<float>());
  // The rows into the work array when the columns come out of it, else
  // into the spectrum, whose columns are then transformed in place.
  const Plans::ColumnPlans& pass = plans_->forward;
  const size_t half = plans_->half;
  fftwf_complex* columns = nullptr;
  fftwf_complex* rows = pass.apart != nullptr || pass.to_columns != nullptr
                            ? plans_->Work(&columns)
                            : out;
  // Rows known to be zero transform to zero.
  float* values = reinterpret_cast<float*>(rows);
  std::fill(
      values + 2 * half * nonzero_rows, values + 2 * half * size_.height, 0.0f);
  if (nonzero_rows > 0) {
    fftwf_execute_dft_r2c(plans_->Rows(true, nonzero_rows),
                          const_cast<float*>(image.ptr<float>()),
                          rows);
  }
  if (pass.apart != nullptr) {
    fftwf_execute_dft(pass.apart, rows, out);
  } else if (pass.to_columns != nullptr) {
    fftwf_execute_dft(pass.to_columns, rows, columns);
    plans_->GatherRows(columns, cv::Range(0, size_.height), out);
  } else {
    fftwf_execute_dft(pass.in_place, out, out);
  }
}

void RealDft::InverseTransform(cv::Mat* spectrum,
                               const cv::Range& rows,
                               cv::Mat* image) const {
  CheckAligned(spectrum->data, "spectrum");
  CheckAligned(image->data, "image");
  const int count = rows.size();
  auto* in = reinterpret_cast<fftwf_complex*>(spectrum->ptr<float>());
  const Plans::ColumnPlans& pass = plans_->inverse;
  fftwf_complex* first = nullptr;
  if (pass.to_columns != nullptr) {
    // Only the rows asked for are gathered, to the work array's front.
    fftwf_complex* columns = nullptr;
    first = plans_->Work(&columns);
    fftwf_execute_dft(pass.to_columns, in, columns);
    plans_->GatherRows(columns, rows, first);
  } else {
    if (pass.apart != nullptr) {
      fftwf_complex* columns = nullptr;
      fftwf_complex* work = plans_->Work(&columns);
      fftwf_execute_dft(pass.apart, in, work);
      in = work;
    } else {
      fftwf_execute_dft(pass.in_place, in, in);
    }
    // The rows' plan runs on arrays aligned as FFTW allocates them; rows
    // that start off that alignment are moved to the front of the work
    // space first (a few kB, against the transform's passes).
    first = in + static_cast<size_t>(rows.start) * plans_->half;
    if (fftwf_alignment_of(reinterpret_cast<float*>(first)) != 0) {
      std::memmove(in, first, sizeof(fftwf_complex) * count * plans_->half);
      first = in;
    }
  }
  fftwf_execute_dft_c2r(plans_->Rows(false, count), first, image->ptr<float>());
}

const char* RealDftBackend() { return "FFTW"; }

}  // namespace dpsfm
