#pragma once

#include <array>
#include <string>
#include <string_view>

namespace noctua::dynamic {

// The 80 COCO classes in the order every COCO-trained YOLO model emits them.
inline constexpr int kNumCocoClasses = 80;
const std::array<std::string_view, kNumCocoClasses>& CocoClassNames();

// Name of a class id ("person" for 0); "class<N>" for ids outside [0, 80).
std::string CocoClassName(int class_id);

// Id of a class name ("dining table" -> 60); -1 when the name is not a COCO class.
int CocoClassId(std::string_view name);

}  // namespace noctua::dynamic
