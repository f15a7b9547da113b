// Discrete Fourier transforms of real series for the comparison (FFTW, planned with
// FFTW_ESTIMATE: no timing runs, so results do not depend on the machine's clock or load).
#pragma once

#include <complex>
#include <cstddef>
#include <vector>

namespace mpdrig {

// The smallest n >= min_size with no prime factor above 7 (FFTW is fast for those).
std::size_t FastFftSize(std::size_t min_size);

// X[k] = sum_n x[n] e^{-2 pi i k n / size}, k = 0..size/2, x zero-padded to `size` (>= x.size()).
std::vector<std::complex<double>> RealDft(const std::vector<double>& x, std::size_t size);

// The inverse of RealDft without the 1/size factor: x[n] = sum_k X[k] e^{+2 pi i k n / size}
// over the full Hermitian spectrum; `spectrum` has size/2 + 1 entries.
std::vector<double> InverseRealDft(const std::vector<std::complex<double>>& spectrum,
                                   std::size_t size);

// Hann window w[n] = 0.5 (1 - cos(2 pi n / (n_total - 1))).
std::vector<double> HannWindow(std::size_t n_total);

}  // namespace mpdrig
