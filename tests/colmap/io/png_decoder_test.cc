// The libdeflate PNG reader against an independent truth: frames filtered
// and compressed here (zlib, with the PNG filters written forwards) must come
// back as the pixels they were made from, and as OpenImageIO (libpng) decodes
// the same bytes; every file it does not take must be left as it was.
#include "dpsfm/colmap/io/png_decoder.h"

#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "dpsfm/colmap/io/dp_images.h"
#include "dpsfm/colmap/util/input_error.h"
#include "tests/colmap/io/frame_oracle.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace {

namespace fs = std::filesystem;

std::string BigEndian32(uint32_t v) {
  return {static_cast<char>(v >> 24),
          static_cast<char>(v >> 16),
          static_cast<char>(v >> 8),
          static_cast<char>(v)};
}

std::string Chunk(const std::string& type, const std::string& data) {
  const std::string body = type + data;
  const uint32_t crc =
      crc32(0, reinterpret_cast<const Bytef*>(body.data()), body.size());
  return BigEndian32(data.size()) + body + BigEndian32(crc);
}

std::string Header(
    int width, int height, int bit_depth, int colour_type, int interlace = 0) {
  std::string data = BigEndian32(width) + BigEndian32(height);
  data += static_cast<char>(bit_depth);
  data += static_cast<char>(colour_type);
  data += std::string(2, '\0');  // compression, filter method
  data += static_cast<char>(interlace);
  return Chunk("IHDR", data);
}

std::string Compress(const std::string& raw) {
  uLongf size = compressBound(raw.size());
  std::string out(size, '\0');
  EXPECT_EQ(compress2(reinterpret_cast<Bytef*>(&out[0]),
                      &size,
                      reinterpret_cast<const Bytef*>(raw.data()),
                      raw.size(),
                      6),
            Z_OK);
  out.resize(size);
  return out;
}

// The PNG filters as an encoder applies them (PNG 1.2, section 6), on rows
// of bytes in file order; the predictor of the Paeth filter as the
// specification writes it.
int PaethPredictor(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return a;
  if (pb <= pc) return b;
  return c;
}

std::string FilterRow(int filter,
                      int bpp,
                      const std::string& row,
                      const std::string& prior) {
  std::string out(row.size(), '\0');
  for (size_t i = 0; i < row.size(); ++i) {
    const int x = static_cast<uint8_t>(row[i]);
    const int a =
        i >= static_cast<size_t>(bpp) ? static_cast<uint8_t>(row[i - bpp]) : 0;
    const int b = static_cast<uint8_t>(prior[i]);
    const int c = i >= static_cast<size_t>(bpp)
                      ? static_cast<uint8_t>(prior[i - bpp])
                      : 0;
    int predicted = 0;
    if (filter == 1) predicted = a;
    if (filter == 2) predicted = b;
    if (filter == 3) predicted = (a + b) / 2;
    if (filter == 4) predicted = PaethPredictor(a, b, c);
    out[i] = static_cast<char>((x - predicted) & 0xFF);
  }
  return out;
}

// A frame (CV_8U or CV_16U, grey or B, G, R) in PNG's order: rows of
// big-endian samples, R, G, B.
std::vector<std::string> RowsInFileOrder(const cv::Mat& frame) {
  std::vector<std::string> rows;
  for (int y = 0; y < frame.rows; ++y) {
    std::string row;
    for (int x = 0; x < frame.cols; ++x) {
      for (int k = 0; k < frame.channels(); ++k) {
        const int i = x * frame.channels() + frame.channels() - 1 - k;
        if (frame.depth() == CV_8U) {
          row += static_cast<char>(frame.ptr<uint8_t>(y)[i]);
        } else {
          const uint16_t v = frame.ptr<uint16_t>(y)[i];
          row += static_cast<char>(v >> 8);
          row += static_cast<char>(v & 0xFF);
        }
      }
    }
    rows.push_back(row);
  }
  return rows;
}

struct PngParts {
  std::string before_idat;  // ancillary chunks after IHDR
  int filter = -1;          // one filter for every row; -1: row y gets y % 5
  size_t idat_size = 97;    // the compressed stream cut into chunks this big
  std::string after_idat;   // chunks between the last IDAT and IEND
};

// The zlib stream of a frame's filtered rows (each a filter byte, then the
// row).
std::string FilteredStream(const cv::Mat& frame, int filter) {
  const std::vector<std::string> rows = RowsInFileOrder(frame);
  const int bpp = static_cast<int>(frame.elemSize());
  std::string raw;
  std::string prior(rows[0].size(), '\0');
  for (size_t y = 0; y < rows.size(); ++y) {
    const int f = filter >= 0 ? filter : static_cast<int>(y % 5);
    raw += static_cast<char>(f);
    raw += FilterRow(f, bpp, rows[y], prior);
    prior = rows[y];
  }
  return Compress(raw);
}

std::string IdatChunks(const std::string& stream, size_t size) {
  std::string chunks = Chunk("IDAT", "");  // an empty one first
  for (size_t at = 0; at < stream.size(); at += size) {
    chunks += Chunk("IDAT", stream.substr(at, size));
  }
  return chunks;
}

std::string EncodePng(const cv::Mat& frame, const PngParts& parts = {}) {
  const int depth = frame.depth() == CV_8U ? 8 : 16;
  const int colour_type = frame.channels() == 3 ? 2 : 0;
  return std::string("\x89PNG\r\n\x1a\n", 8) +
         Header(frame.cols, frame.rows, depth, colour_type) +
         parts.before_idat +
         IdatChunks(FilteredStream(frame, parts.filter), parts.idat_size) +
         parts.after_idat + Chunk("IEND", "");
}

cv::Mat RandomFrame(
    int width, int height, int depth, int channels, unsigned seed) {
  cv::Mat frame(height, width, CV_MAKETYPE(depth, channels));
  cv::RNG rng(seed);
  rng.fill(frame, cv::RNG::UNIFORM, 0, depth == CV_8U ? 256 : 65536);
  // Smooth runs too, so that the filters' predictions are mostly right.
  if (height > 2) frame.row(1).copyTo(frame.row(2));
  return frame;
}

TEST(DecodePng, EveryFilterAtEveryDepthAsMadeAndAsOpenImageIO) {
  const std::vector<cv::Size> sizes = {{1, 1}, {7, 5}, {33, 21}};
  unsigned seed = 1;
  for (const int depth : {CV_8U, CV_16U}) {
    for (const int channels : {1, 3}) {
      for (const cv::Size& size : sizes) {
        for (const int filter : {-1, 0, 1, 2, 3, 4}) {
          const cv::Mat frame =
              RandomFrame(size.width, size.height, depth, channels, seed++);
          PngParts parts;
          parts.filter = filter;
          // Chunks libpng reads (gamma, significant bits, text) and leaves
          // the pixels alone for.
          parts.before_idat = Chunk("gAMA", BigEndian32(45455)) +
                              Chunk("sBIT", std::string(channels, '\x0c')) +
                              Chunk("tEXt", std::string("Software\0test", 13));
          parts.after_idat = Chunk("tEXt", std::string("Comment\0x", 9));
          parts.idat_size = 1 + seed % 50;
          std::string bytes = EncodePng(frame, parts);
          const cv::Mat oiio = test::DecodedByOpenImageIO(bytes);
          cv::Mat pixels;
          SCOPED_TRACE(::testing::Message()
                       << "depth " << depth << " channels " << channels << " "
                       << size << " filter " << filter);
          ASSERT_EQ(DecodePng(&bytes, &pixels), PngDecoding::kDecoded);
          EXPECT_TRUE(bytes.empty());
          EXPECT_TRUE(test::SameBits(pixels, frame));
          EXPECT_TRUE(test::SameBits(pixels, oiio));
        }
      }
    }
  }
}

TEST(DecodePng, OneLargeIdatChunkAndWideRows) {
  // One IDAT chunk, as some writers make them, and rows longer than the
  // frame is high (a single spare row holds the filter bytes).
  const cv::Mat frame = RandomFrame(3001, 2, CV_16U, 3, 7);
  PngParts parts;
  parts.idat_size = 1 << 30;
  std::string bytes = EncodePng(frame, parts);
  cv::Mat pixels;
  ASSERT_EQ(DecodePng(&bytes, &pixels), PngDecoding::kDecoded);
  EXPECT_TRUE(test::SameBits(pixels, frame));
  // And a frame much higher than wide: one spare row per row of filter
  // bytes the frame's own rows cannot hold.
  const cv::Mat tall = RandomFrame(1, 300, CV_8U, 1, 8);
  bytes = EncodePng(tall);
  ASSERT_EQ(DecodePng(&bytes, &pixels), PngDecoding::kDecoded);
  EXPECT_TRUE(test::SameBits(pixels, tall));
}

TEST(DecodePng, LeavesEveryOtherFileAsItWas) {
  const cv::Mat frame = RandomFrame(9, 6, CV_8U, 3, 3);
  const std::string signature("\x89PNG\r\n\x1a\n", 8);
  const std::string idat = IdatChunks(FilteredStream(frame, -1), 40);
  const std::string end = Chunk("IEND", "");
  std::string bad_crc = Chunk("tEXt", std::string("a\0b", 3));
  bad_crc[bad_crc.size() - 1] ^= 1;
  std::string bad_idat_crc = Chunk("IDAT", Compress(std::string(61, '\0')));
  bad_idat_crc[bad_idat_crc.size() - 1] ^= 1;
  const std::string header = Header(9, 6, 8, 2);
  const std::vector<std::pair<std::string, std::string>> files = {
      {"interlaced", signature + Header(9, 6, 8, 2, 1) + idat + end},
      {"palette",
       signature + Header(9, 6, 8, 3) + Chunk("PLTE", std::string(9, '\x10')) +
           idat + end},
      {"4-bit grey", signature + Header(9, 6, 4, 0) + idat + end},
      {"RGBA", signature + Header(9, 6, 8, 6) + idat + end},
      {"grey and alpha", signature + Header(9, 6, 16, 4) + idat + end},
      {"transparent colour",
       signature + header + Chunk("tRNS", std::string(6, '\0')) + idat + end},
      {"suggested palette",
       signature + header + Chunk("PLTE", std::string(9, '\x10')) + idat + end},
      {"unknown critical chunk",
       signature + header + Chunk("ABCD", "x") + idat + end},
      {"ancillary CRC wrong", signature + header + bad_crc + idat + end},
      {"IDAT CRC wrong", signature + header + bad_idat_crc + end},
      {"IDAT chunks apart",
       signature + header + Chunk("IDAT", "") +
           Chunk("tEXt", std::string("a\0b", 3)) + idat + end},
      {"no IEND", signature + header + idat},
      {"no IDAT", signature + header + end},
      {"IHDR not first", signature + Chunk("tEXt", "a") + header + idat + end},
      {"truncated", (signature + header + idat).substr(0, 60)},
      {"zero width", signature + Header(0, 6, 8, 2) + idat + end},
      {"JPEG", std::string("\xFF\xD8\xFF\xE0", 4) + std::string(60, '\0')},
      {"empty", ""},
  };
  for (const auto& [name, file] : files) {
    std::string bytes = file;
    cv::Mat pixels;
    EXPECT_EQ(DecodePng(&bytes, &pixels), PngDecoding::kNotDecoded) << name;
    EXPECT_EQ(bytes, file) << name;
    EXPECT_TRUE(pixels.empty()) << name;
  }
}

TEST(DecodePng, CorruptPixelDataIsLeftToOpenImageIOToWord) {
  const cv::Mat frame = RandomFrame(9, 6, CV_16U, 1, 4);
  const std::string signature("\x89PNG\r\n\x1a\n", 8);
  const std::string header = Header(9, 6, 16, 0);
  const std::string end = Chunk("IEND", "");
  const int row_bytes = 9 * 2;
  std::string unknown_filter(6 * (row_bytes + 1), '\0');
  unknown_filter[3 * (row_bytes + 1)] = 5;
  std::string stream = FilteredStream(frame, 2);
  std::string damaged = stream;
  damaged[damaged.size() / 2] ^= 0x55;
  const std::vector<std::pair<std::string, std::string>> files = {
      {"unknown filter", Compress(unknown_filter)},
      {"a row short", Compress(std::string(5 * (row_bytes + 1), '\0'))},
      {"a row too many", Compress(std::string(7 * (row_bytes + 1), '\0'))},
      {"stream damaged", damaged},
      {"stream cut", stream.substr(0, stream.size() - 6)},
  };
  test::TempDir dir;
  for (const auto& [name, compressed] : files) {
    const std::string file =
        signature + header + IdatChunks(compressed, 30) + end;
    std::string bytes = file;
    cv::Mat pixels;
    EXPECT_EQ(DecodePng(&bytes, &pixels), PngDecoding::kFailed) << name;
    EXPECT_TRUE(pixels.empty()) << name;
    // ReadDPFrameFile makes of it what OpenImageIO does: its pixels where
    // it decodes the file, an error naming the file where it does not.
    const fs::path path = fs::path(dir.path()) / "frame.png";
    test::WriteTextFile(path.string(), file);
    const cv::Mat oiio = test::DecodedByOpenImageIO(file);
    if (oiio.empty()) {
      EXPECT_THROW(ReadDPFrameFile(path.string()), InputError) << name;
    } else {
      EXPECT_TRUE(test::SameBits(ReadDPFrameFile(path.string()).pixels, oiio))
          << name;
    }
  }
}

// A header is checked against the data before anything is allocated: a
// 10^6 x 10^6 frame over a few bytes of stream is refused by this reader
// (deflate expands at most 1032:1) and by ReadDPFrameFile, whose
// OpenImageIO would take the header as it is, with one line naming the
// file.
TEST(DecodePng, HeaderClaimingMoreThanTheDataCanHoldIsRefused) {
  const std::string file = std::string("\x89PNG\r\n\x1a\n", 8) +
                           Header(1000000, 1000000, 16, 2) +
                           Chunk("IDAT", Compress(std::string(64, '\0'))) +
                           Chunk("IEND", "");
  std::string bytes = file;
  cv::Mat pixels;
  EXPECT_EQ(DecodePng(&bytes, &pixels), PngDecoding::kFailed);
  EXPECT_TRUE(pixels.empty());
  test::TempDir dir;
  const std::string path = dir / "huge.png";
  test::WriteTextFile(path, file);
  try {
    ReadDPFrameFile(path);
    ADD_FAILURE() << "a 10^6 x 10^6 header was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("header claims 1000000 x 1000000"),
              std::string::npos)
        << e.what();
  }
}

// 3000 files made from a valid one: cut anywhere, bytes flipped anywhere
// (CRCs then mostly wrong: left to OpenImageIO), and header fields and
// stream bytes changed under right CRCs (this reader's own paths; some
// streams left intact, which decode where the header fits). Each is
// decoded, left as it was or refused; a tenth go through ReadDPFrameFile,
// which returns pixels or throws InputError. None crashes.
// The textbook filter reversal (PNG 1.2, section 9), a byte at a time.
void UnfilterByTheBook(int filter,
                       int bpp,
                       const std::vector<uint8_t>& prior,
                       std::vector<uint8_t>* row,
                       size_t row_bytes) {
  std::vector<uint8_t>& r = *row;
  for (size_t i = 0; i < row_bytes; ++i) {
    const int a = i >= static_cast<size_t>(bpp) ? r[i - bpp] : 0;
    const int b = prior[i];
    const int c = i >= static_cast<size_t>(bpp) ? prior[i - bpp] : 0;
    int predictor = 0;
    if (filter == 1) predictor = a;
    if (filter == 2) predictor = b;
    if (filter == 3) predictor = (a + b) / 2;
    if (filter == 4) predictor = PaethPredictor(a, b, c);
    r[i] = static_cast<uint8_t>(r[i] + predictor);
  }
}

// Both forms of the decoder's pixel lanes (the vector extension's and the
// plain ones) reverse every filter as the specification does, for every
// pixel size the decoder meets.
TEST(DecodePng, PixelLanesOfBothFormsUnfilterAsTheBook) {
  std::mt19937 rng(5);
  for (const int bpp : {1, 2, 3, 4, 6, 8}) {
    for (int filter = 0; filter <= 4; ++filter) {
      const size_t row_bytes = static_cast<size_t>(bpp) * 37;
      std::vector<uint8_t> prior(row_bytes + 8), row(row_bytes + 8);
      for (uint8_t& v : prior) v = static_cast<uint8_t>(rng());
      for (uint8_t& v : row) v = static_cast<uint8_t>(rng());
      std::vector<uint8_t> book = row;
      UnfilterByTheBook(filter, bpp, prior, &book, row_bytes);
      for (const bool portable : {false, true}) {
        std::vector<uint8_t> got = row;
        ASSERT_TRUE(internal::UnfilterRowForTest(
            filter, bpp, row_bytes, prior.data(), got.data(), portable));
        EXPECT_TRUE(std::equal(got.begin(), got.begin() + row_bytes,
                               book.begin()))
            << "filter " << filter << ", " << bpp << " bytes per pixel, "
            << (portable ? "portable" : "vector") << " lanes";
      }
    }
  }
  std::vector<uint8_t> prior(16), row(16);
  EXPECT_FALSE(internal::UnfilterRowForTest(5, 3, 6, prior.data(), row.data(),
                                            false));
}

TEST(DecodePng, MutatedFilesAreDecodedOrRefusedNeverACrash) {
  const cv::Mat frame = RandomFrame(24, 16, CV_16U, 3, 11);
  const std::string valid = EncodePng(frame);
  const std::string stream = FilteredStream(frame, 4);
  std::mt19937 rng(20261207);
  auto uniform = [&](size_t n) {
    return std::uniform_int_distribution<size_t>(0, n - 1)(rng);
  };
  test::TempDir dir;
  int decoded = 0, refused = 0, left = 0, read = 0, input_errors = 0;
  for (int i = 0; i < 3000; ++i) {
    std::string file;
    switch (i % 3) {
      case 0:
        file = valid.substr(0, uniform(valid.size()));
        break;
      case 1:
        file = valid;
        for (int k = 0; k < 1 + static_cast<int>(uniform(4)); ++k) {
          file[uniform(file.size())] ^= static_cast<char>(1 << uniform(8));
        }
        break;
      default: {
        const int j = i / 3;
        const bool random_size = j % 3 == 0;
        const uint32_t width =
            random_size ? static_cast<uint32_t>(uniform(2000000)) : 24;
        const uint32_t height =
            random_size ? static_cast<uint32_t>(uniform(2000000)) : 16;
        std::string damaged = stream;
        if (j % 2 == 0) {
          damaged[uniform(damaged.size())] ^=
              static_cast<char>(1 << uniform(8));
        }
        file = std::string("\x89PNG\r\n\x1a\n", 8) +
               Header(width, height, i / 3 % 7 ? 16 : 8, i / 3 % 11 ? 2 : 0) +
               IdatChunks(damaged, 1 + uniform(200)) +
               Chunk("IEND", "");
      }
    }
    std::string bytes = file;
    cv::Mat pixels;
    const PngDecoding result = DecodePng(&bytes, &pixels);
    decoded += result == PngDecoding::kDecoded;
    refused += result == PngDecoding::kFailed;
    left += result == PngDecoding::kNotDecoded;
    if (result == PngDecoding::kNotDecoded) {
      EXPECT_EQ(bytes, file) << i;  // left as it was
    }
    if (i % 10 == 0) {
      const std::string path = dir / "mutated.png";
      test::WriteTextFile(path, file);
      try {
        read += !ReadDPFrameFile(path).pixels.empty();
      } catch (const InputError&) {
        ++input_errors;
      }
    }
  }
  std::printf("3000 mutated PNGs: %d decoded, %d refused, %d left to "
              "OpenImageIO; 300 read: %d frames, %d input errors\n",
              decoded, refused, left, read, input_errors);
  EXPECT_EQ(decoded + refused + left, 3000);
  EXPECT_EQ(read + input_errors, 300);
  EXPECT_GT(decoded, 0);
  EXPECT_GT(refused, 0);
  EXPECT_GT(left, 0);
}

TEST(DecodePng, RealCapturesAsOpenImageIO) {
  const std::string real = test::RealDpDir();
  if (real.empty()) GTEST_SKIP() << "no real DP captures (../shared/realdp)";
  int frames = 0;
  for (const auto& entry : fs::recursive_directory_iterator(real)) {
    if (entry.path().extension() != ".png" || frames >= 8) continue;
    std::string bytes = test::ReadTextFile(entry.path().string());
    const cv::Mat oiio = test::DecodedByOpenImageIO(bytes);
    cv::Mat pixels;
    ASSERT_EQ(DecodePng(&bytes, &pixels), PngDecoding::kDecoded)
        << entry.path();
    EXPECT_TRUE(test::SameBits(pixels, oiio)) << entry.path();
    ++frames;
  }
  EXPECT_EQ(frames, 8);
}

}  // namespace
}  // namespace dpsfm
