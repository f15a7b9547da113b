#include "model/analysis/spectrum.h"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "model/common/status.h"

namespace mpdrig {
namespace {

bool IsSmooth(std::size_t n) {
  for (std::size_t p : {2, 3, 5, 7}) {
    while (n % p == 0) n /= p;
  }
  return n == 1;
}

// FFTW's aligned buffers, released on scope exit.
struct FftwBuffer {
  explicit FftwBuffer(std::size_t bytes) : data(fftw_malloc(bytes)) {
    MPDRIG_CHECK(data != nullptr);
  }
  ~FftwBuffer() { fftw_free(data); }
  FftwBuffer(const FftwBuffer&) = delete;
  FftwBuffer& operator=(const FftwBuffer&) = delete;
  void* data;
};

}  // namespace

std::size_t FastFftSize(std::size_t min_size) {
  std::size_t n = std::max<std::size_t>(min_size, 1);
  while (!IsSmooth(n)) ++n;
  return n;
}

std::vector<std::complex<double>> RealDft(const std::vector<double>& x, std::size_t size) {
  MPDRIG_CHECK(size >= x.size() && size > 0);
  const std::size_t bins = size / 2 + 1;
  FftwBuffer in(sizeof(double) * size);
  FftwBuffer out(sizeof(fftw_complex) * bins);
  double* in_data = static_cast<double*>(in.data);
  fftw_complex* out_data = static_cast<fftw_complex*>(out.data);
  // Plan before filling: FFTW_ESTIMATE does not touch the arrays, but the contract allows it.
  fftw_plan plan = fftw_plan_dft_r2c_1d(static_cast<int>(size), in_data, out_data, FFTW_ESTIMATE);
  MPDRIG_CHECK(plan != nullptr);
  for (std::size_t i = 0; i < size; ++i) in_data[i] = i < x.size() ? x[i] : 0.0;
  fftw_execute(plan);
  fftw_destroy_plan(plan);
  std::vector<std::complex<double>> spectrum(bins);
  for (std::size_t k = 0; k < bins; ++k) spectrum[k] = {out_data[k][0], out_data[k][1]};
  return spectrum;
}

std::vector<double> InverseRealDft(const std::vector<std::complex<double>>& spectrum,
                                   std::size_t size) {
  const std::size_t bins = size / 2 + 1;
  MPDRIG_CHECK(spectrum.size() == bins);
  FftwBuffer in(sizeof(fftw_complex) * bins);
  FftwBuffer out(sizeof(double) * size);
  fftw_complex* in_data = static_cast<fftw_complex*>(in.data);
  double* out_data = static_cast<double*>(out.data);
  fftw_plan plan = fftw_plan_dft_c2r_1d(static_cast<int>(size), in_data, out_data, FFTW_ESTIMATE);
  MPDRIG_CHECK(plan != nullptr);
  for (std::size_t k = 0; k < bins; ++k) {
    in_data[k][0] = spectrum[k].real();
    in_data[k][1] = spectrum[k].imag();
  }
  fftw_execute(plan);  // c2r overwrites its input; it is ours
  fftw_destroy_plan(plan);
  return std::vector<double>(out_data, out_data + size);
}

std::vector<double> HannWindow(std::size_t n_total) {
  std::vector<double> w(n_total, 1.0);
  if (n_total < 2) return w;
  for (std::size_t n = 0; n < n_total; ++n) {
    w[n] = 0.5 * (1.0 - std::cos(2.0 * std::numbers::pi * n / (n_total - 1)));
  }
  return w;
}

WelchSegmenter::WelchSegmenter(std::size_t max_length)
    : max_length_(std::max<std::size_t>(max_length, 8)), hop_(max_length_ / 2) {}

std::optional<std::size_t> WelchSegmenter::Push() {
  ++count_;
  if (count_ >= max_length_ && (count_ - max_length_) % hop_ == 0) return max_length_;
  return std::nullopt;
}

std::optional<std::size_t> WelchSegmenter::Finish() const {
  if (count_ < max_length_) return count_;  // the whole series, one segment
  if ((count_ - max_length_) % hop_ != 0) return max_length_;
  return std::nullopt;  // the last regular segment ended at the last sample
}

std::size_t WelchSegmenter::SegmentLength(std::size_t samples, std::size_t max_length) {
  return std::min(samples, std::max<std::size_t>(max_length, 8));
}

std::size_t WelchSegmenter::SegmentCount(std::size_t samples, std::size_t max_length) {
  const std::size_t length = std::max<std::size_t>(max_length, 8);
  if (samples <= length) return 1;
  const std::size_t hop = length / 2;
  const std::size_t regular = (samples - length) / hop + 1;
  return regular + ((samples - length) % hop != 0 ? 1 : 0);
}

void SampleRing::CopyLast(std::size_t length, std::vector<double>* out) const {
  MPDRIG_CHECK(length <= values_.size());
  out->resize(length);
  const std::size_t capacity = values_.size();
  std::size_t index = (next_ + capacity - length) % capacity;
  for (std::size_t i = 0; i < length; ++i) {
    (*out)[i] = values_[index];
    index = index + 1 == capacity ? 0 : index + 1;
  }
}

}  // namespace mpdrig
