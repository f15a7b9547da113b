// A seeded byte-level mutator for the parser fuzz tests: each call returns a mutation of one of
// the seed inputs (bit flips, byte insertions and deletions, spans duplicated or cut, whole lines
// swapped, and tokens that have broken parsers before: huge and tiny numbers, nan, inf, signs,
// separators, line ends, comment marks, invalid UTF-8). The same seed gives the same inputs, so a
// failure is reproduced by its seed and iteration, which the tests print. Header-only.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <iterator>
#include <random>
#include <string>
#include <vector>

namespace mpdrig::testing {

class Mutator {
 public:
  Mutator(std::vector<std::string> seeds, std::uint64_t seed)
      : seeds_(std::move(seeds)), random_(seed) {}

  std::string Next() {
    std::string text = seeds_[Pick(seeds_.size())];
    const int rounds = 1 + static_cast<int>(Pick(8));
    for (int i = 0; i < rounds; ++i) Mutate(&text);
    return text;
  }

 private:
  std::size_t Pick(std::size_t n) {
    return n == 0 ? 0 : std::uniform_int_distribution<std::size_t>(0, n - 1)(random_);
  }

  void Mutate(std::string* text) {
    static const char* const kTokens[] = {"1e308",
                                          "-1e308",
                                          "1e-320",
                                          "nan",
                                          "NaN",
                                          "inf",
                                          "-inf",
                                          "0",
                                          "-0",
                                          "1e17",
                                          "4294967295",
                                          "18446744073709551616",
                                          "99999999999999999999999",
                                          "0x1p3",
                                          ",",
                                          ",,",
                                          "\n",
                                          "\r\n",
                                          "\r",
                                          "#",
                                          "# rig-log: 2\n",
                                          "# atmospheric_pressure_pa: 1\n",
                                          "time_s",
                                          "PT1_barg",
                                          "_barg",
                                          " ",
                                          "\t",
                                          "\"",
                                          "\xef\xbb\xbf",
                                          "\xff\xfe",
                                          "\xc3",
                                          "\x00",
                                          "{",
                                          "}",
                                          ":",
                                          "effect {",
                                          "choke_point {",
                                          "param { key: \"k\" value: 1 }",
                                          "name: \"\"",
                                          "1e9999",
                                          "-",
                                          "+",
                                          ".",
                                          "e",
                                          "E-"};
    const std::size_t size = text->size();
    switch (Pick(8)) {
      case 0:  // flip a bit
        if (size > 0) (*text)[Pick(size)] ^= static_cast<char>(1u << Pick(8));
        break;
      case 1:  // insert a random byte
        text->insert(text->begin() + static_cast<std::ptrdiff_t>(Pick(size + 1)),
                     static_cast<char>(Pick(256)));
        break;
      case 2:  // delete a span
        if (size > 0) {
          const std::size_t at = Pick(size);
          text->erase(at, 1 + Pick(std::min<std::size_t>(16, size - at)));
        }
        break;
      case 3: {  // insert a token
        const std::string token = kTokens[Pick(std::size(kTokens))];
        text->insert(Pick(size + 1), token.empty() ? std::string(1, '\0') : token);
        break;
      }
      case 4:  // replace a span with a token
        if (size > 0) {
          const std::size_t at = Pick(size);
          text->replace(at, 1 + Pick(std::min<std::size_t>(8, size - at)),
                        kTokens[Pick(std::size(kTokens))]);
        }
        break;
      case 5:  // duplicate a span
        if (size > 0) {
          const std::size_t at = Pick(size);
          const std::string span = text->substr(at, 1 + Pick(64));
          text->insert(Pick(size + 1), span);
        }
        break;
      case 6:  // cut the text short
        text->resize(Pick(size + 1));
        break;
      default: {  // swap two lines
        std::vector<std::string> lines;
        std::size_t start = 0;
        for (std::size_t i = 0; i <= size; ++i) {
          if (i == size || (*text)[i] == '\n') {
            lines.push_back(text->substr(start, i - start));
            start = i + 1;
          }
        }
        if (lines.size() >= 2) {
          std::swap(lines[Pick(lines.size())], lines[Pick(lines.size())]);
          std::string joined;
          for (std::size_t i = 0; i < lines.size(); ++i) {
            joined += lines[i];
            if (i + 1 < lines.size()) joined += '\n';
          }
          *text = joined;
        }
        break;
      }
    }
  }

  std::vector<std::string> seeds_;
  std::mt19937_64 random_;
};

// Iterations for a fuzz test: MPDRIG_FUZZ_ITERATIONS if set (a longer run by hand or in a
// nightly job), else `default_count`; and the seed: MPDRIG_FUZZ_SEED, else `default_seed`.
inline long FuzzIterations(long default_count) {
  const char* given = std::getenv("MPDRIG_FUZZ_ITERATIONS");
  return given != nullptr ? std::atol(given) : default_count;
}
inline std::uint64_t FuzzSeed(std::uint64_t default_seed) {
  const char* given = std::getenv("MPDRIG_FUZZ_SEED");
  return given != nullptr ? std::strtoull(given, nullptr, 10) : default_seed;
}

}  // namespace mpdrig::testing
