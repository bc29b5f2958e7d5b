#pragma once
// The project label set for indoor mapping: 8-bit class ids (METHODS.md B1 LUT), names and a
// fixed colour palette. Model-specific class ids are mapped to these at the segmenter boundary
// (segmentation/class_mapping) and nowhere else.
#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

namespace semap {

using ClassId = uint8_t;

enum class Label : ClassId {
  kUnlabelled = 0,  ///< no label / ignored in evaluation
  kWall, kFloor, kCeiling, kDoor, kWindow,
  kTable, kChair, kSofa, kBed, kBookcase, kCabinet, kShelf, kDesk,
  kMonitor, kLaptop, kKeyboard, kMouse, kPhone, kBook,
  kCup, kBottle, kBowl, kBox, kPlant, kVase, kClock, kLamp,
  kSink, kRefrigerator, kMicrowave, kOven, kToilet, kPerson,
  kBag, kPillow, kRemote, kTeddy,
  kOther,  ///< a recognised object of a class outside this set
  // Appended after kOther (issue 38) so that ids stored in saved maps keep their values; new
  // classes go here, before kCount. kOther is therefore NOT the largest id.
  kCurtain, kPicture, kRug, kMirror,
  kCount
};

constexpr int kNumClasses = static_cast<int>(Label::kCount);
static_assert(kNumClasses <= 256, "class ids must fit 8 bits");

constexpr ClassId id(Label l) { return static_cast<ClassId>(l); }

struct Rgb8 {
  uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb8&) const = default;
};

/// Name of a class id ("unlabelled", "wall", ...); "other" for ids out of range.
std::string_view class_name(ClassId c);
/// Inverse of class_name; nullopt for unknown names.
std::optional<ClassId> class_from_name(std::string_view name);
/// The fixed palette (documented in README): colour of a class id.
Rgb8 class_colour(ClassId c);
/// "Stuff" (not countable objects: never object-map instances): the structural classes
/// wall/floor/ceiling/door/window and the surface coverings curtain/rug/mirror (COCO panoptic
/// also counts curtain, rug and mirror as stuff). Everything else, picture included, is an object.
bool is_stuff(ClassId c);

}  // namespace semap
