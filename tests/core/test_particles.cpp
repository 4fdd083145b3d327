#include <gtest/gtest.h>

#include <numeric>
#include <random>

#include "geohaz/core/particles.hpp"

namespace geohaz {
namespace {

struct Pressure {
  using type = double;
  static constexpr const char* label = "pressure";
  static constexpr const char* unit = "Pa";
};
struct Flag {
  using type = std::uint8_t;
  static constexpr const char* label = "flag";
  static constexpr const char* unit = "1";
};
struct Stress {
  using type = Mat<3>;
  static constexpr const char* label = "stress";
  static constexpr const char* unit = "Pa";
};

using Store = ParticleStore<Position<2>, Velocity<2>, ParticleId, Pressure, Flag, Stress>;

Store make(std::size_t n) {
  Store s;
  s.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    s.get<Position<2>>()[i] = Vec2(double(i), 2.0 * i);
    s.get<Velocity<2>>()[i] = Vec2(-double(i), 0.5 * i);
    s.get<ParticleId>()[i] = static_cast<std::int64_t>(i);
    s.get<Pressure>()[i] = 10.0 * i;
    s.get<Flag>()[i] = static_cast<std::uint8_t>(i % 3);
    s.get<Stress>()[i] = Mat3::Constant(double(i));
  }
  return s;
}

// Every field of particle k must still describe the particle whose id it carries.
void expect_consistent(const Store& s) {
  for (std::size_t k = 0; k < s.size(); ++k) {
    const double i = static_cast<double>(s.get<ParticleId>()[k]);
    EXPECT_EQ(s.get<Position<2>>()[k], Vec2(i, 2.0 * i));
    EXPECT_EQ(s.get<Velocity<2>>()[k], Vec2(-i, 0.5 * i));
    EXPECT_EQ(s.get<Pressure>()[k], 10.0 * i);
    EXPECT_EQ(s.get<Flag>()[k], static_cast<std::uint8_t>(static_cast<int>(i) % 3));
    EXPECT_EQ(s.get<Stress>()[k], Mat3::Constant(i));
  }
}

TEST(ParticleStore, ResizeZeroInitialisesEveryField) {
  Store s;
  s.resize(4);
  EXPECT_EQ(s.size(), 4u);
  EXPECT_EQ(s.get<Position<2>>()[3], Vec2::Zero());
  EXPECT_EQ(s.get<Stress>()[2], Mat3::Zero());
  EXPECT_EQ(s.get<Flag>()[1], 0);
  EXPECT_TRUE(Store::has<Pressure>());
  EXPECT_FALSE(Store::has<Mass>());
}

TEST(ParticleStore, AppendReturnsFirstNewIndex) {
  Store s = make(5);
  EXPECT_EQ(s.append(3), 5u);
  EXPECT_EQ(s.size(), 8u);
  EXPECT_EQ(s.get<Pressure>().size(), 8u);
  EXPECT_EQ(s.get<Pressure>()[7], 0.0);
}

TEST(ParticleStore, ReorderMovesEveryFieldTogether) {
  Store s = make(200);
  std::vector<std::uint32_t> perm(200);
  std::iota(perm.begin(), perm.end(), 0u);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(7));
  s.reorder(perm);
  for (std::size_t k = 0; k < 200; ++k) EXPECT_EQ(s.get<ParticleId>()[k], static_cast<std::int64_t>(perm[k]));
  expect_consistent(s);
}

TEST(ParticleStore, RemoveCompactsAndKeepsOrder) {
  Store s = make(10);
  std::vector<std::uint8_t> mask(10, 0);
  mask[0] = mask[4] = mask[9] = 1;
  EXPECT_EQ(s.remove_if(mask), 3u);
  ASSERT_EQ(s.size(), 7u);
  const std::vector<std::int64_t> ids = {1, 2, 3, 5, 6, 7, 8};
  for (std::size_t k = 0; k < ids.size(); ++k) EXPECT_EQ(s.get<ParticleId>()[k], ids[k]);
  expect_consistent(s);
}

TEST(ParticleStore, SizeMismatchIsRejected) {
  Store s = make(3);
  std::vector<std::uint8_t> mask(2, 0);
  EXPECT_THROW(s.remove_if(mask), std::invalid_argument);
  std::vector<std::uint32_t> perm = {0, 1};
  EXPECT_THROW(s.reorder(perm), std::invalid_argument);
}

TEST(ParticleStore, ForEachFieldVisitsAllInOrder) {
  Store s = make(2);
  std::vector<std::string> labels;
  s.for_each_field([&](auto tag, const auto&) { labels.emplace_back(decltype(tag)::label); });
  EXPECT_EQ(labels, (std::vector<std::string>{"position", "velocity", "id", "pressure", "flag", "stress"}));
  EXPECT_EQ(Store::bytes_per_particle(), 16u + 16u + 8u + 8u + 1u + 72u);
}

}  // namespace
}  // namespace geohaz
