// TextTableReader's fields and numbers: what the readers of every dataset and trajectory file rest on. The numbers are
// read by std::from_chars (faster than strtod, no locale); these cases pin down that it reads what strtod read and
// refuses the same, naming file and line.
#include "ov_core/io/csv.h"
#include "ov_core/types/errors.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

namespace {

/// A reader of `text` (written to a temporary file) positioned on its first row.
struct OneRow {
  ovtest::TempDir dir;
  std::unique_ptr<ovton::core::TextTableReader> reader;
  std::vector<std::string> fields;
  OneRow(const std::string &text, char sep) {
    const std::string file = dir / "t.csv";
    ovtest::write_text(file, text);
    reader = std::make_unique<ovton::core::TextTableReader>(file, sep);
    EXPECT_TRUE(reader->next(fields));
  }
};

} // namespace

TEST(CsvNumbers, ReadsWhatStrtodReads) {
  for (const char *text : {"1.5", "+1.5", "-0.0052359877559829882", "9.81e+00", "1E-3", "0x1p3", "1e-400", "7",
                           "-2.2250738585072014e-308", "4.9406564584124654e-324", ".5", "5."}) {
    OneRow r(std::string("# header\n") + text + ",1\n", ',');
    ASSERT_EQ(r.fields.size(), 2u) << text;
    EXPECT_EQ(r.reader->to_double(r.fields[0], "x"), std::strtod(text, nullptr)) << text;
  }
  for (const char *text : {"1403715273262142976", "+12", "-5", "0"}) {
    OneRow r(std::string(text) + ",x\n", ',');
    EXPECT_EQ(r.reader->to_int64(r.fields[0], "t"), std::strtoll(text, nullptr, 10)) << text;
  }
}

TEST(CsvNumbers, RefusesWhatIsNotAFiniteNumber) {
  for (const char *text : {"zero", "1.5x", "1..5", "+-1", "-", "+", "1e400", "-1e400", "nan", "inf", "-inf", "1,5"}) {
    OneRow r(std::string("1,2\n3,") + text + "\n", ';');
    ASSERT_TRUE(r.reader->next(r.fields));
    try {
      r.reader->to_double(r.fields[0], "angle");
      ADD_FAILURE() << "accepted '" << text << "'";
    } catch (const ovton::core::DataError &e) {
      EXPECT_NE(std::string(e.what()).find(":2"), std::string::npos) << e.what(); // the line
      EXPECT_NE(std::string(e.what()).find("angle"), std::string::npos) << e.what();
    }
  }
  for (const char *text : {"9223372036854775808", "12.0", "1e3", "0x10", "12 3", "+-1"}) {
    OneRow r(std::string(text) + "\n", ',');
    EXPECT_THROW(r.reader->to_int64(r.fields[0], "t"), ovton::core::DataError) << text;
  }
}

TEST(CsvNumbers, FieldsWithoutTheirBlanksAndRowsReused) {
  OneRow r("\xEF\xBB\xBF# c\n timestamp , a ,b\n 1 ,  2.5\t, x \n\n#mid\n3,4\n", ',');
  EXPECT_EQ(r.fields, (std::vector<std::string>{"1", "2.5", "x"}));
  EXPECT_EQ(r.reader->line(), 3);
  ASSERT_TRUE(r.reader->next(r.fields));
  EXPECT_EQ(r.fields, (std::vector<std::string>{"3", "4"})); // a shorter row after a longer one
  EXPECT_EQ(r.reader->line(), 6);
  EXPECT_FALSE(r.reader->next(r.fields));
  ASSERT_EQ(r.reader->comments().size(), 3u);
  EXPECT_EQ(r.reader->comments()[0], "# c");
  EXPECT_EQ(r.reader->comments()[1], "timestamp , a ,b");

  OneRow t("1.0  2\t\t3 \n", ' ');
  EXPECT_EQ(t.fields, (std::vector<std::string>{"1.0", "2", "3"}));
  OneRow e("1,,3,\n", ',');
  EXPECT_EQ(e.fields, (std::vector<std::string>{"1", "", "3", ""}));
}
