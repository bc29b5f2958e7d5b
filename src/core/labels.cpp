#include "semap/core/labels.hpp"

#include <string>

namespace semap {
namespace {

struct ClassInfo {
  std::string_view name;
  Rgb8 colour;
};

// Palette: distinct, saturated colours for objects, muted ones for structure (loosely after
// the NYUv2/ScanNet palettes). Fixed: changing it changes every labelled mesh.
constexpr std::array<ClassInfo, kNumClasses> kClasses{{
    {"unlabelled", {0, 0, 0}},
    {"wall", {174, 199, 232}},
    {"floor", {152, 223, 138}},
    {"ceiling", {220, 220, 200}},
    {"door", {214, 39, 40}},
    {"window", {197, 176, 213}},
    {"table", {255, 152, 150}},
    {"chair", {188, 189, 34}},
    {"sofa", {140, 86, 75}},
    {"bed", {255, 187, 120}},
    {"bookcase", {148, 103, 189}},
    {"cabinet", {31, 119, 180}},
    {"shelf", {196, 156, 148}},
    {"desk", {247, 182, 210}},
    {"monitor", {23, 190, 207}},
    {"laptop", {66, 188, 102}},
    {"keyboard", {219, 219, 141}},
    {"mouse", {140, 57, 197}},
    {"phone", {202, 185, 52}},
    {"book", {51, 176, 203}},
    {"cup", {255, 127, 14}},
    {"bottle", {44, 160, 44}},
    {"bowl", {227, 119, 194}},
    {"box", {158, 218, 229}},
    {"plant", {0, 128, 0}},
    {"vase", {112, 128, 144}},
    {"clock", {96, 207, 209}},
    {"lamp", {255, 255, 0}},
    {"sink", {112, 128, 144}},
    {"refrigerator", {255, 69, 0}},
    {"microwave", {178, 34, 34}},
    {"oven", {128, 0, 0}},
    {"toilet", {0, 0, 128}},
    {"person", {255, 0, 255}},
    {"bag", {128, 128, 0}},
    {"pillow", {255, 215, 180}},
    {"remote", {0, 255, 127}},
    {"teddy", {210, 105, 30}},
    {"other", {127, 127, 127}},
    {"curtain", {219, 112, 147}},
    {"picture", {0, 100, 100}},
    {"rug", {128, 64, 128}},
    {"mirror", {75, 0, 130}},
}};

}  // namespace

std::string_view class_name(ClassId c) {
  return c < kNumClasses ? kClasses[c].name : kClasses[id(Label::kOther)].name;
}

std::optional<ClassId> class_from_name(std::string_view name) {
  for (int i = 0; i < kNumClasses; ++i)
    if (kClasses[i].name == name) return static_cast<ClassId>(i);
  return std::nullopt;
}

Rgb8 class_colour(ClassId c) {
  return c < kNumClasses ? kClasses[c].colour : kClasses[id(Label::kOther)].colour;
}

bool is_stuff(ClassId c) {
  return (c >= id(Label::kWall) && c <= id(Label::kWindow)) || c == id(Label::kCurtain) || c == id(Label::kRug) ||
         c == id(Label::kMirror);
}

}  // namespace semap
