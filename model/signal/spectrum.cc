#include "model/signal/spectrum.h"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>

#include "model/common/status.h"

namespace mpdrig {
namespace {

// FFTW's planner (plan creation and destruction) is not thread-safe, only fftw_execute is. The
// model has no threads, but a caller may run model functions on several (diagnose's candidates,
// design.md): one lock around planning keeps them reentrant.
std::mutex& PlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

bool IsSmooth(std::size_t n) {
  for (std::size_t p : {2, 3, 5, 7}) {
    while (n % p == 0) n /= p;
  }
  return n == 1;
}

}  // namespace

std::size_t FastFftSize(std::size_t min_size) {
  std::size_t n = std::max<std::size_t>(min_size, 1);
  while (!IsSmooth(n)) ++n;
  return n;
}

RealFft::RealFft(std::size_t size) : size_(size) {
  MPDRIG_CHECK(size > 0);
  const std::lock_guard<std::mutex> lock(PlannerMutex());
  const std::size_t bins = size / 2 + 1;
  real_ = static_cast<double*>(fftw_malloc(sizeof(double) * size));
  complex_ = fftw_malloc(sizeof(fftw_complex) * bins);
  MPDRIG_CHECK(real_ != nullptr && complex_ != nullptr);
  auto* spectrum = static_cast<fftw_complex*>(complex_);
  // FFTW_ESTIMATE: no timing runs, so the plan (and the result) does not depend on the machine's
  // load; it does not touch the arrays while planning.
  fftw_plan forward = fftw_plan_dft_r2c_1d(static_cast<int>(size), real_, spectrum, FFTW_ESTIMATE);
  fftw_plan inverse = fftw_plan_dft_c2r_1d(static_cast<int>(size), spectrum, real_, FFTW_ESTIMATE);
  MPDRIG_CHECK(forward != nullptr && inverse != nullptr);
  forward_ = forward;
  inverse_ = inverse;
}

RealFft::~RealFft() {
  const std::lock_guard<std::mutex> lock(PlannerMutex());
  fftw_destroy_plan(static_cast<fftw_plan>(forward_));
  fftw_destroy_plan(static_cast<fftw_plan>(inverse_));
  fftw_free(real_);
  fftw_free(complex_);
}

void RealFft::Forward(const std::vector<double>& x, std::vector<std::complex<double>>* spectrum) {
  MPDRIG_CHECK(size_ >= x.size());
  for (std::size_t i = 0; i < size_; ++i) real_[i] = i < x.size() ? x[i] : 0.0;
  fftw_execute(static_cast<fftw_plan>(forward_));
  const auto* out = static_cast<const fftw_complex*>(complex_);
  spectrum->resize(size_ / 2 + 1);
  for (std::size_t k = 0; k < spectrum->size(); ++k) (*spectrum)[k] = {out[k][0], out[k][1]};
}

void RealFft::Inverse(const std::vector<std::complex<double>>& spectrum, std::vector<double>* x) {
  MPDRIG_CHECK(spectrum.size() == size_ / 2 + 1);
  auto* in = static_cast<fftw_complex*>(complex_);
  for (std::size_t k = 0; k < spectrum.size(); ++k) {
    in[k][0] = spectrum[k].real();
    in[k][1] = spectrum[k].imag();
  }
  fftw_execute(static_cast<fftw_plan>(inverse_));  // c2r overwrites its input; it is ours
  x->assign(real_, real_ + size_);
}

std::vector<std::complex<double>> RealDft(const std::vector<double>& x, std::size_t size) {
  MPDRIG_CHECK(size >= x.size() && size > 0);
  RealFft fft(size);
  std::vector<std::complex<double>> spectrum;
  fft.Forward(x, &spectrum);
  return spectrum;
}

std::vector<double> InverseRealDft(const std::vector<std::complex<double>>& spectrum,
                                   std::size_t size) {
  MPDRIG_CHECK(spectrum.size() == size / 2 + 1);
  RealFft fft(size);
  std::vector<double> x;
  fft.Inverse(spectrum, &x);
  return x;
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
