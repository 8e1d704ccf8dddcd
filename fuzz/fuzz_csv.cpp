// libFuzzer target: the numeric text table reader every CSV/TUM reader is built on. First byte picks the separator.
#include "fuzz_util.h"
#include "ov_core/io/csv.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1)
    return 0;
  const char sep = (data[0] & 1) ? ',' : ' ';
  const std::string file =
      ovfuzz::write_file("table.csv", std::string(reinterpret_cast<const char *>(data + 1), size - 1));
  ovfuzz::expect_clean([&] {
    ovton::core::TextTableReader r(file, sep);
    std::vector<std::string> f;
    while (r.next(f))
      for (size_t i = 0; i < f.size(); ++i)
        ovfuzz::expect_clean([&] { i == 0 ? (void)r.to_int64(f[i], "stamp") : (void)r.to_double(f[i], "value"); });
  });
  return 0;
}
