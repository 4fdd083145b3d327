// The name table of a family of laws (name_table.hpp): names, sentences, lookup and help text
// follow the variant's alternatives, in their order.
#include <gtest/gtest.h>

#include <variant>

#include "geohaz/core/name_table.hpp"

namespace {

struct Alpha {
  static constexpr const char* name = "alpha";
  static constexpr const char* summary = "the first law";
  double a = 1.5;
};
struct Beta {
  static constexpr const char* name = "beta";
  static constexpr const char* summary = "the second law";
  int b = 7;
};
using Law = std::variant<Alpha, Beta>;
using Names = geohaz::NameTable<Law>;

TEST(NameTable, NamesAndSentencesFollowTheVariantOrder) {
  static_assert(Names::names.size() == 2);
  EXPECT_EQ(Names::names[0], "alpha");
  EXPECT_EQ(Names::names[1], "beta");
  EXPECT_EQ(Names::summaries[1], "the second law");
  EXPECT_EQ(Names::choices(), (std::vector<std::string>{"alpha", "beta"}));
  EXPECT_EQ(Names::help("law"), "law: alpha = the first law; beta = the second law");
}

TEST(NameTable, FromNameGivesTheLawWithItsDefaultsAndNothingForAnUnknownName) {
  const auto b = Names::from_name("beta");
  ASSERT_TRUE(b.has_value());
  ASSERT_TRUE(std::holds_alternative<Beta>(*b));
  EXPECT_EQ(std::get<Beta>(*b).b, 7);
  EXPECT_EQ(Names::name_of(*b), "beta");
  EXPECT_EQ(Names::name_of(Law{Alpha{}}), "alpha");
  EXPECT_FALSE(Names::from_name("gamma").has_value());
  EXPECT_FALSE(Names::from_name("Alpha").has_value());  // names are exact
}

TEST(NameTable, AnExhaustiveVisitSetsEachLawsParameters) {
  Law law = *Names::from_name("alpha");
  std::visit(geohaz::Overloaded{[](Alpha& a) { a.a = 2.5; }, [](Beta& b) { b.b = 3; }}, law);
  EXPECT_EQ(std::get<Alpha>(law).a, 2.5);
}

}  // namespace
