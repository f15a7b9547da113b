// Discrete Fourier transforms of real series for the comparison (FFTW, planned with
// FFTW_ESTIMATE: no timing runs, so results do not depend on the machine's clock or load).
#pragma once

#include <complex>
#include <cstddef>
#include <optional>
#include <vector>

namespace mpdrig {

// The smallest n >= min_size with no prime factor above 7 (FFTW is fast for those).
std::size_t FastFftSize(std::size_t min_size);

// A real DFT of one size planned once, for many transforms of that size: planning (FFTW's
// twiddle factors) costs about as much as a transform. Same results as RealDft / InverseRealDft.
class RealFft {
 public:
  explicit RealFft(std::size_t size);
  ~RealFft();
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;
  std::size_t size() const { return size_; }
  // As RealDft(x, size()).
  void Forward(const std::vector<double>& x, std::vector<std::complex<double>>* spectrum);
  // As InverseRealDft(spectrum, size()).
  void Inverse(const std::vector<std::complex<double>>& spectrum, std::vector<double>* x);

 private:
  std::size_t size_;
  double* real_ = nullptr;
  void* complex_ = nullptr;  // fftw_complex[size / 2 + 1]
  void* forward_ = nullptr;  // fftw_plan
  void* inverse_ = nullptr;
};

// X[k] = sum_n x[n] e^{-2 pi i k n / size}, k = 0..size/2, x zero-padded to `size` (>= x.size()).
std::vector<std::complex<double>> RealDft(const std::vector<double>& x, std::size_t size);

// The inverse of RealDft without the 1/size factor: x[n] = sum_k X[k] e^{+2 pi i k n / size}
// over the full Hermitian spectrum; `spectrum` has size/2 + 1 entries.
std::vector<double> InverseRealDft(const std::vector<std::complex<double>>& spectrum,
                                   std::size_t size);

// Hann window w[n] = 0.5 (1 - cos(2 pi n / (n_total - 1))).
std::vector<double> HannWindow(std::size_t n_total);

// Where the Welch segments of a series of unknown length lie, decided as its samples arrive
// (Welch 1967: averaged periodograms of overlapping windowed segments). A series of at most
// `max_length` samples is one segment, the whole series: the plain periodogram. A longer one has
// segments of max_length samples every max_length / 2 (50 % overlap, where the Hann window's
// weights add up to a constant), and, if those do not end at the last sample, one more that does,
// so every sample is used. Every segment ends at the sample just pushed (or, at Finish, the last
// one), so a ring of max_length samples (SampleRing) holds it.
class WelchSegmenter {
 public:
  explicit WelchSegmenter(std::size_t max_length);
  std::size_t max_length() const { return max_length_; }
  // Counts one sample; the length of the segment that ends with it, if one does.
  std::optional<std::size_t> Push();
  // After the last sample: the length of the final segment, if it is still due.
  std::optional<std::size_t> Finish() const;
  // The segment length a series of `samples` samples gets.
  static std::size_t SegmentLength(std::size_t samples, std::size_t max_length);
  // How many segments it gets.
  static std::size_t SegmentCount(std::size_t samples, std::size_t max_length);

 private:
  std::size_t max_length_;
  std::size_t hop_;
  std::size_t count_ = 0;
};

// The last `capacity` values of a stream.
class SampleRing {
 public:
  explicit SampleRing(std::size_t capacity) : values_(capacity) {}
  void Push(double value) {
    values_[next_] = value;
    next_ = next_ + 1 == values_.size() ? 0 : next_ + 1;
  }
  // The last `length` (<= capacity, <= values pushed) values, oldest first.
  void CopyLast(std::size_t length, std::vector<double>* out) const;

 private:
  std::vector<double> values_;
  std::size_t next_ = 0;
};

}  // namespace mpdrig
