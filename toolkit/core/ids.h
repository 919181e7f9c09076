// Strong ids for values that cross interfaces (style.md point 11).
#pragma once

#include <compare>
#include <cstdint>
#include <functional>

namespace ptc {

template <class Tag>
struct Id {
  std::uint32_t value{};
  constexpr Id() = default;
  constexpr explicit Id(std::uint32_t v) : value(v) {}
  constexpr auto operator<=>(const Id&) const = default;
};

using TriangleId = Id<struct TriangleTag>;
using VertexId = Id<struct VertexTag>;
using ClusterId = Id<struct ClusterTag>;

}  // namespace ptc

template <class Tag>
struct std::hash<ptc::Id<Tag>> {
  std::size_t operator()(const ptc::Id<Tag>& id) const noexcept { return std::hash<std::uint32_t>{}(id.value); }
};
