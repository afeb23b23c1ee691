// Procedural textures (see textures.hpp). Every texture is drawn with OpenCV primitives from its own
// seeded generator, so it is identical on every visit and in every run.
#include "toposlam/sim/textures.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <opencv2/imgproc.hpp>

namespace toposlam::sim {

namespace {

int pixels(double metres) { return std::max(4, static_cast<int>(std::lround(metres * kTexturePixelsPerMetre))); }

int randomInt(std::mt19937_64& rng, int low, int high) {
  return std::uniform_int_distribution<int>(low, std::max(low, high))(rng);
}

cv::Scalar randomColour(std::mt19937_64& rng, int low, int high) {
  return cv::Scalar(randomInt(rng, low, high), randomInt(rng, low, high), randomInt(rng, low, high));
}

/// Rows of short dark dashes, like lines of text.
void drawTextLines(cv::Mat& image, std::mt19937_64& rng, cv::Rect area, const cv::Scalar& ink, int line_height) {
  for (int y = area.y + line_height; y < area.y + area.height; y += line_height) {
    int x = area.x + randomInt(rng, 0, line_height);
    const int line_end = area.x + area.width - randomInt(rng, 0, area.width / 3);
    while (x < line_end) {
      const int word = randomInt(rng, line_height, line_height * 4);
      const int thickness = std::max(1, line_height / 4);
      cv::line(image, {x, y}, {std::min(x + word, line_end), y}, ink, thickness);
      // a few ascenders make the strokes corner-rich, like letters
      for (int k = x + 2; k < std::min(x + word, line_end); k += randomInt(rng, 3, 9)) {
        cv::line(image, {k, y}, {k, y - line_height / 2}, ink, std::max(1, thickness / 2));
      }
      x += word + randomInt(rng, line_height / 2, line_height);
    }
  }
}

void drawChecker(cv::Mat& image, cv::Rect area, int cell, const cv::Scalar& a, const cv::Scalar& b) {
  for (int y = area.y; y < area.y + area.height; y += cell) {
    for (int x = area.x; x < area.x + area.width; x += cell) {
      const bool odd = (((x - area.x) / cell) + ((y - area.y) / cell)) % 2 != 0;
      cv::rectangle(image, cv::Rect(x, y, std::min(cell, area.x + area.width - x), std::min(cell, area.y + area.height - y)),
                    odd ? a : b, cv::FILLED);
    }
  }
}

}  // namespace

cv::Mat makePosterTexture(std::uint64_t seed, double width_m, double height_m) {
  std::mt19937_64 rng(seed);
  const int w = pixels(width_m), h = pixels(height_m);
  cv::Mat image(h, w, CV_8UC3, randomColour(rng, 150, 250));
  const int margin = std::max(3, w / 16);
  const cv::Rect inner(margin, margin, w - 2 * margin, h - 2 * margin);
  // A picture block, several coloured rectangles, a checker patch and text lines.
  const int picture_h = inner.height * randomInt(rng, 35, 55) / 100;
  cv::rectangle(image, cv::Rect(inner.x, inner.y, inner.width, picture_h), randomColour(rng, 20, 200), cv::FILLED);
  const int shapes = randomInt(rng, 3, 8);
  for (int i = 0; i < shapes; ++i) {
    const int sw = randomInt(rng, inner.width / 8, inner.width / 2);
    const int sh = randomInt(rng, picture_h / 6, picture_h / 2);
    const int sx = inner.x + randomInt(rng, 0, inner.width - sw);
    const int sy = inner.y + randomInt(rng, 0, std::max(0, picture_h - sh));
    if (randomInt(rng, 0, 2) == 0) {
      cv::circle(image, {sx + sw / 2, sy + sh / 2}, std::max(2, std::min(sw, sh) / 2), randomColour(rng, 0, 255), cv::FILLED);
    } else {
      cv::rectangle(image, cv::Rect(sx, sy, sw, sh), randomColour(rng, 0, 255), cv::FILLED);
    }
  }
  const int cell = std::max(4, inner.width / randomInt(rng, 8, 14));
  const cv::Rect checker(inner.x + inner.width - 3 * cell, inner.y + picture_h + cell / 2, 3 * cell, 2 * cell);
  if (checker.y + checker.height < inner.y + inner.height) {
    drawChecker(image, checker, cell, cv::Scalar(20, 20, 20), cv::Scalar(240, 240, 240));
  }
  const cv::Rect text(inner.x, inner.y + picture_h + cell / 2, inner.width - 4 * cell,
                      inner.height - picture_h - cell / 2);
  if (text.width > 8 && text.height > 8) drawTextLines(image, rng, text, randomColour(rng, 0, 80), randomInt(rng, 7, 12));
  cv::rectangle(image, cv::Rect(0, 0, w, h), cv::Scalar(40, 40, 40), 2);
  return image;
}

cv::Mat makeBoardTexture(std::uint64_t seed, double width_m, double height_m) {
  std::mt19937_64 rng(seed);
  const int w = pixels(width_m), h = pixels(height_m);
  cv::Mat image(h, w, CV_8UC3, cv::Scalar(246, 246, 244));
  const cv::Scalar inks[] = {{40, 40, 40}, {160, 60, 30}, {40, 40, 190}, {50, 140, 40}};
  const int blocks = randomInt(rng, 2, 4);
  for (int b = 0; b < blocks; ++b) {
    const cv::Rect area(randomInt(rng, 8, w / 2), randomInt(rng, 8, h / 2), randomInt(rng, w / 4, w / 2 - 8),
                        randomInt(rng, h / 5, h / 2 - 8));
    drawTextLines(image, rng, area, inks[randomInt(rng, 0, 3)], randomInt(rng, 10, 16));
  }
  // a hand-drawn diagram: boxes joined by lines
  cv::Point last(randomInt(rng, 10, w - 40), randomInt(rng, 10, h - 30));
  for (int i = 0; i < 3; ++i) {
    const cv::Point next(randomInt(rng, 10, w - 40), randomInt(rng, 10, h - 30));
    cv::rectangle(image, cv::Rect(next.x, next.y, 30, 20), inks[randomInt(rng, 0, 3)], 2);
    cv::line(image, last, next, inks[0], 1);
    last = next;
  }
  cv::rectangle(image, cv::Rect(0, 0, w, h), cv::Scalar(150, 150, 155), 5);
  cv::rectangle(image, cv::Rect(w / 10, h - 8, w / 5, 6), cv::Scalar(120, 120, 125), cv::FILLED);  // pen tray
  return image;
}

cv::Mat makeShelfTexture(std::uint64_t seed, double width_m, double height_m, const cv::Vec3b& body_bgr) {
  std::mt19937_64 rng(seed);
  const int w = pixels(width_m), h = pixels(height_m);
  const cv::Scalar body(body_bgr[0], body_bgr[1], body_bgr[2]);
  cv::Mat image(h, w, CV_8UC3, body);
  const int side = std::max(3, pixels(0.03));
  const int board = std::max(3, pixels(0.025));
  const int shelves = std::max(2, static_cast<int>(height_m / 0.38));
  const int row_h = (h - board) / shelves;
  for (int s = 0; s < shelves; ++s) {
    const int top = board + s * row_h;
    const int bottom = top + row_h - board;
    cv::rectangle(image, cv::Rect(side, top, w - 2 * side, row_h - board), cv::Scalar(25, 25, 28), cv::FILLED);
    int x = side;
    while (x < w - side - 4) {
      const int book_w = randomInt(rng, 4, 14);
      const int book_h = (bottom - top) * randomInt(rng, 60, 95) / 100;
      if (randomInt(rng, 0, 9) == 0) {  // a gap between books
        x += book_w * 2;
        continue;
      }
      const cv::Scalar colour = randomColour(rng, 20, 230);
      const cv::Rect book(x, bottom - book_h, std::min(book_w, w - side - x), book_h);
      cv::rectangle(image, book, colour, cv::FILLED);
      cv::line(image, {book.x + 1, book.y + book_h / 4}, {book.x + book.width - 2, book.y + book_h / 4},
               cv::Scalar(230, 230, 230) - colour, 1);
      x += book_w + 1;
    }
  }
  return image;
}

cv::Mat makeDeskTexture(std::uint64_t seed, double width_m, double height_m, const cv::Vec3b& body_bgr) {
  std::mt19937_64 rng(seed);
  const int w = pixels(width_m), h = pixels(height_m);
  const cv::Scalar body(body_bgr[0], body_bgr[1], body_bgr[2]);
  cv::Mat image(h, w, CV_8UC3, cv::Scalar(30, 30, 32));  // shadow under the desk
  const int top = std::max(3, pixels(0.04));
  const int leg = std::max(3, pixels(0.05));
  cv::rectangle(image, cv::Rect(0, 0, w, top), body, cv::FILLED);
  cv::rectangle(image, cv::Rect(0, 0, leg, h), body * 0.8, cv::FILLED);
  cv::rectangle(image, cv::Rect(w - leg, 0, leg, h), body * 0.8, cv::FILLED);
  // a drawer block on one side
  const int drawer_w = w / 3;
  const int drawer_x = randomInt(rng, 0, 1) == 0 ? leg : w - leg - drawer_w;
  cv::rectangle(image, cv::Rect(drawer_x, top, drawer_w, h - top), body * 0.9, cv::FILLED);
  for (int d = 1; d < 3; ++d) {
    const int y = top + d * (h - top) / 3;
    cv::line(image, {drawer_x, y}, {drawer_x + drawer_w, y}, cv::Scalar(20, 20, 20), 1);
    cv::rectangle(image, cv::Rect(drawer_x + drawer_w / 2 - 6, y - (h - top) / 6 - 1, 12, 3), cv::Scalar(200, 200, 200),
                  cv::FILLED);
  }
  return image;
}

cv::Mat makePersonTexture(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const int w = pixels(0.5), h = pixels(1.7);
  cv::Mat image(h, w, CV_8UC3, cv::Scalar(0, 0, 0));
  const cv::Scalar skin = randomInt(rng, 0, 1) == 0 ? cv::Scalar(150, 180, 220) : cv::Scalar(70, 100, 140);
  const cv::Scalar hair = randomColour(rng, 10, 80);
  const cv::Scalar shirt = randomColour(rng, 30, 230);
  const cv::Scalar trousers = randomColour(rng, 20, 120);
  const int head_h = h * 13 / 100;
  cv::rectangle(image, cv::Rect(0, 0, w, h), cv::Scalar(1, 1, 1), cv::FILLED);  // 1 = transparent marker
  cv::ellipse(image, {w / 2, head_h / 2 + 2}, {w / 5, head_h / 2}, 0, 0, 360, skin, cv::FILLED);
  cv::ellipse(image, {w / 2, head_h / 3}, {w / 5, head_h / 3}, 0, 180, 360, hair, cv::FILLED);
  cv::rectangle(image, cv::Rect(w / 8, head_h + 4, w * 3 / 4, h * 40 / 100), shirt, cv::FILLED);
  cv::rectangle(image, cv::Rect(w / 5, head_h + 4 + h * 40 / 100, w * 3 / 5, h - head_h - 4 - h * 40 / 100), trousers,
                cv::FILLED);
  cv::line(image, {w / 2, head_h + 4 + h * 40 / 100 + 10}, {w / 2, h}, cv::Scalar(1, 1, 1), 3);  // between the legs
  return image;
}

}  // namespace toposlam::sim
