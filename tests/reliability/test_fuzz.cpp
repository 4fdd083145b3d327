#include <gtest/gtest.h>
TEST(Fuzz, Placeholder) {}
