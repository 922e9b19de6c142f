// QuoteInput (sim/core/quote.h): a short, printable prefix of a user's input.
#include "sim/core/quote.h"

#include <string>

#include <gtest/gtest.h>

namespace sportsim {
namespace {

TEST(QuoteInputTest, ShortPrintablePrefixBetweenMarks) {
  EXPECT_EQ(QuoteInput("white"), "\"white\"");
  EXPECT_EQ(QuoteInput(std::string("a\nb\0c\x7f\xc3\xa9", 8)), "\"a?b?c???\"");
  EXPECT_EQ(QuoteInput(std::string(30, 'x')), "\"" + std::string(24, 'x') + "...\"");
  EXPECT_EQ(QuoteInput(std::string(24, 'x')), "\"" + std::string(24, 'x') + "\"");
  EXPECT_EQ(QuoteInput("hole", 2, '\''), "'ho...'");
  EXPECT_EQ(QuoteInput(""), "\"\"");
}

}  // namespace
}  // namespace sportsim
