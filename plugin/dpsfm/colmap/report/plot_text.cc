#include "dpsfm/colmap/report/plot_text.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include <opencv2/imgproc.hpp>

namespace dpsfm {
namespace plot {
namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

}  // namespace

std::string Printable(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (u == '\n' || u == '\t' || u == '\r') {
      out += ' ';
    } else if (u < 32 || u >= 127) {
      out += '?';
    } else {
      out += c;
    }
  }
  return out;
}

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

std::string FormatValue(double value) {
  if (!Finite(value)) return "n/a";
  const double a = std::abs(value);
  if (a != 0 && (a < 1e-3 || a >= 1e6)) return Format("%.3g", value);
  return Format("%.4g", value);
}

cv::Size TextSize(const std::string& text, double scale, int thickness) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, scale, thickness, &baseline);
}

void PutText(cv::Mat& canvas,
             const std::string& text,
             cv::Point anchor,
             double scale,
             const cv::Scalar& colour,
             int thickness,
             Align align) {
  const std::string printable = Printable(text);
  const cv::Size size = TextSize(printable, scale, thickness);
  if (align == Align::kCenter) anchor.x -= size.width / 2;
  if (align == Align::kRight) anchor.x -= size.width;
  cv::putText(
      canvas, printable, anchor, kFont, scale, colour, thickness, cv::LINE_AA);
}

std::string Ellipsize(const std::string& text,
                      double scale,
                      int thickness,
                      int max_width) {
  const std::string out = Printable(text);
  if (TextSize(out, scale, thickness).width <= max_width) return out;
  // Characters leave from the middle: a view's name keeps its start and its
  // end (its number and extension).
  for (size_t keep = out.size(); keep-- > 0;) {
    const std::string shorter = out.substr(0, (keep + 1) / 2) + "..." +
                                out.substr(out.size() - keep / 2);
    if (TextSize(shorter, scale, thickness).width <= max_width) return shorter;
  }
  return "...";
}

std::vector<std::string> WrapText(const std::string& text,
                                  double scale,
                                  int thickness,
                                  int max_width,
                                  int max_lines) {
  std::vector<std::string> words;
  std::istringstream stream(Printable(text));
  std::string word;
  while (stream >> word) words.push_back(word);
  std::vector<std::string> lines;
  std::string line;
  for (size_t i = 0; i < words.size(); ++i) {
    const std::string candidate =
        line.empty() ? words[i] : line + " " + words[i];
    if (line.empty() ||
        TextSize(candidate, scale, thickness).width <= max_width) {
      line = candidate;
      continue;
    }
    lines.push_back(line);
    line = words[i];
  }
  if (!line.empty()) lines.push_back(line);
  if (static_cast<int>(lines.size()) > max_lines) {
    std::string last = lines[max_lines - 1];
    for (size_t i = max_lines; i < lines.size(); ++i) last += " " + lines[i];
    lines.resize(max_lines);
    lines.back() = last;
  }
  for (std::string& l : lines) l = Ellipsize(l, scale, thickness, max_width);
  return lines;
}

int PutWrapped(cv::Mat& canvas,
               const std::string& text,
               int x,
               int y,
               int max_width,
               int max_lines,
               double scale,
               const cv::Scalar& colour,
               int thickness,
               int line_height) {
  if (line_height <= 0) {
    line_height = TextSize("Ag", scale, thickness).height * 17 / 10;
  }
  const std::vector<std::string> lines =
      WrapText(text, scale, thickness, max_width, max_lines);
  for (const std::string& line : lines) {
    PutText(canvas, line, {x, y}, scale, colour, thickness);
    y += line_height;
  }
  return y;
}

void PutVerticalText(cv::Mat& canvas,
                     const std::string& text,
                     cv::Point centre,
                     double scale,
                     const cv::Scalar& colour,
                     int thickness) {
  const std::string printable = Printable(text);
  int baseline = 0;
  const cv::Size size =
      cv::getTextSize(printable, kFont, scale, thickness, &baseline);
  cv::Mat flat(size.height + baseline + 4, size.width + 4, CV_8UC3, kWhite);
  cv::putText(flat,
              printable,
              {2, size.height + 2},
              kFont,
              scale,
              colour,
              thickness,
              cv::LINE_AA);
  cv::Mat rotated;
  cv::rotate(flat, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
  cv::Rect target(centre.x - rotated.cols / 2,
                  centre.y - rotated.rows / 2,
                  rotated.cols,
                  rotated.rows);
  const cv::Rect clipped = target & cv::Rect(0, 0, canvas.cols, canvas.rows);
  if (clipped.area() <= 0) return;
  // Darken-only blend: the patch's white background leaves the canvas as is.
  cv::Mat destination = canvas(clipped);
  cv::Mat source = rotated(cv::Rect(clipped.x - target.x,
                                    clipped.y - target.y,
                                    clipped.width,
                                    clipped.height));
  cv::min(destination, source, destination);
}

namespace {

// Every word is kept: a long reason takes as many lines as it needs.
constexpr int kAllLines = 1000;

// Text wrapped to a width, with how it is drawn: `shift` px added to the
// baseline before its first line.
struct TextBlock {
  std::vector<std::string> lines;
  double scale;
  cv::Scalar colour;
  int thickness;
  int line_height;
  int shift;
};

TextBlock Wrapped(const std::string& text,
                  int width,
                  double scale,
                  const cv::Scalar& colour,
                  int thickness,
                  int line_height,
                  int shift = 0) {
  TextBlock block{{}, scale, colour, thickness, line_height, shift};
  if (!text.empty()) {
    block.lines = WrapText(text, scale, thickness, width, kAllLines);
  }
  return block;
}

// The alert (bold, red), the title (bold) and the subtitle of a picture of
// `width` px, each wrapped whole.
std::vector<TextBlock> HeaderBlocks(int width,
                                    const std::string& alert,
                                    const std::string& title,
                                    const std::string& subtitle) {
  const int text_width = width - 40;
  return {Wrapped(alert, text_width, 0.62, kFailureColour, 2, 26),
          Wrapped(title, text_width, 0.62, kTextColour, 2, 26),
          Wrapped(subtitle, text_width, 0.48, kMutedText, 1, 20, -4)};
}

// The first baseline of each block's lines, from `first_baseline` on; the
// rows the blocks need (their last baseline plus room for descenders), at
// least min_rows.
std::vector<int> Baselines(const std::vector<TextBlock>& blocks,
                           int first_baseline,
                           int min_rows,
                           int* rows) {
  std::vector<int> starts;
  int y = first_baseline;
  int last = 0;
  for (const TextBlock& block : blocks) {
    if (block.lines.empty()) {
      starts.push_back(y);
      continue;
    }
    y += block.shift;
    starts.push_back(y);
    last = y + (static_cast<int>(block.lines.size()) - 1) * block.line_height;
    y = last + block.line_height;
  }
  *rows = std::max(min_rows, last + 12);
  return starts;
}

// A white strip of `like`'s width and type with the blocks drawn from x.
cv::Mat DrawBlocks(const cv::Mat& like,
                   const std::vector<TextBlock>& blocks,
                   int x,
                   int first_baseline,
                   int min_rows) {
  int rows = 0;
  const std::vector<int> starts =
      Baselines(blocks, first_baseline, min_rows, &rows);
  cv::Mat strip(rows, like.cols, like.type(), kWhite);
  for (size_t b = 0; b < blocks.size(); ++b) {
    int y = starts[b];
    for (const std::string& line : blocks[b].lines) {
      PutText(strip,
              line,
              {x, y},
              blocks[b].scale,
              blocks[b].colour,
              blocks[b].thickness);
      y += blocks[b].line_height;
    }
  }
  return strip;
}

constexpr int kHeaderX = 20, kHeaderBaseline = 30;

}  // namespace

int HeaderRows(int width,
               int min_rows,
               const std::string& alert,
               const std::string& title,
               const std::string& subtitle) {
  int rows = 0;
  Baselines(HeaderBlocks(width, alert, title, subtitle),
            kHeaderBaseline,
            min_rows,
            &rows);
  return rows;
}

cv::Mat HeaderStrip(const cv::Mat& like,
                    int min_rows,
                    const std::string& alert,
                    const std::string& title,
                    const std::string& subtitle) {
  return DrawBlocks(like,
                    HeaderBlocks(like.cols, alert, title, subtitle),
                    kHeaderX,
                    kHeaderBaseline,
                    min_rows);
}

cv::Mat WithHeader(const cv::Mat& body,
                   int body_top,
                   const std::string& alert,
                   const std::string& title,
                   const std::string& subtitle) {
  cv::Mat out;
  cv::vconcat(HeaderStrip(body, body_top, alert, title, subtitle),
              body.rowRange(body_top, body.rows),
              out);
  return out;
}

cv::Mat WithFooter(const cv::Mat& body,
                   int body_bottom,
                   const std::string& text,
                   double scale,
                   int line_height) {
  const TextBlock block =
      Wrapped(text, body.cols - 60, scale, kTextColour, 1, line_height);
  cv::Mat out;
  cv::vconcat(
      body.rowRange(0, body_bottom),
      DrawBlocks(body, {block}, 30, line_height, body.rows - body_bottom),
      out);
  return out;
}

}  // namespace plot
}  // namespace dpsfm
