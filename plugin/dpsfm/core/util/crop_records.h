// Records kept per pair of crops (a patch's left and right views), known by
// their bytes: what the searches' caches hold from one run to the next. A
// pair is found by HashBytes, then SameBytes on both crops; the hash is
// taken when a pair is added, so crops changed in place later are not found
// by their new contents.
#pragma once

#include <cstdint>
#include <set>
#include <unordered_map>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/util/matrices.h"

namespace dpsfm {

template <typename Record>
class CropRecords {
 public:
  // The record of (left, right) for which `also_same(record)` holds, else a
  // new one, default-made (*added then true) and holding the crops.
  template <typename AlsoSame>
  Record* Find(const cv::Mat& left,
               const cv::Mat& right,
               const AlsoSame& also_same,
               bool* added) {
    const uint64_t hash = HashBytes(right, HashBytes(left));
    const auto range = entries_.equal_range(hash);
    for (auto it = range.first; it != range.second; ++it) {
      Entry& entry = it->second;
      if (also_same(entry.record) && SameBytes(entry.left, left) &&
          SameBytes(entry.right, right)) {
        *added = false;
        return &entry.record;
      }
    }
    Entry& entry = entries_.emplace(hash, Entry())->second;
    entry.left = left;
    entry.right = right;
    *added = true;
    return &entry.record;
  }

  // Drops every record not in `used` (nulls allowed).
  void KeepOnly(const std::vector<Record*>& used) {
    const std::set<const Record*> keep(used.begin(), used.end());
    for (auto it = entries_.begin(); it != entries_.end();) {
      it = keep.count(&it->second.record) > 0 ? std::next(it)
                                              : entries_.erase(it);
    }
  }

  void Clear() { entries_.clear(); }
  int Size() const { return static_cast<int>(entries_.size()); }

 private:
  struct Entry {
    cv::Mat left, right;  // held: the crops the record is known by
    Record record;
  };
  std::unordered_multimap<uint64_t, Entry> entries_;
};

}  // namespace dpsfm
