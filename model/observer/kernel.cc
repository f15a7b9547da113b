#include "model/observer/kernel.h"

#include <cmath>
#include <string>

namespace mpdrig::observer {

KernelSolution::KernelSolution(double sigma, int cells)
    : sigma_(sigma),
      cells_(cells),
      puu_((cells + 1) * (cells + 1), 0.0),
      pvu_((cells + 1) * (cells + 1), 0.0) {}

Result<KernelSolution> KernelSolution::Solve(double sigma, int cells) {
  if (cells < 2 || cells > 20000) {
    return Status::Error("kernel grid cells must be in [2, 20000], got " + std::to_string(cells));
  }
  if (!std::isfinite(sigma) || sigma < 0.0 || sigma > 10.0) {
    return Status::Error("kernel sigma must be finite and in [0, 10], got " +
                         std::to_string(sigma));
  }
  KernelSolution k(sigma, cells);
  const int m = cells;
  const double h = 1.0 / m;
  // Source coefficients: d(P^uu)/ds = -a(x) P^vu along (1,1); d(P^vu)/ds = b(x) P^uu along (1,-1).
  auto a = [sigma](double x) { return sigma * std::exp(2.0 * sigma * x); };
  auto b = [sigma](double x) { return sigma * std::exp(-2.0 * sigma * x); };
  auto puu_diag = [sigma](double x) { return -0.5 * sigma * (1.0 + sigma * x); };
  auto pvu_diag = [sigma](double x) { return 0.5 * sigma * std::exp(-2.0 * sigma * x); };

  for (int sum = 0; sum <= 2 * m; ++sum) {
    const int i_top = sum / 2;  // the node on (or next to) the main diagonal
    const int i_low = sum > m ? sum - m : 0;
    for (int i = i_top; i >= i_low; --i) {
      const int j = sum - i;
      const double x = i * h;
      if (i == j) {
        k.puu_[k.Index(i, j)] = puu_diag(x);
        k.pvu_[k.Index(i, j)] = pvu_diag(x);
        continue;
      }
      // P^vu along the antidiagonal, from the previous node towards the main diagonal:
      //   Pvu = pvu_from - (step/2) [b(x_from) Puu_from + b(x) Puu]  =: c2 - d2 Puu
      double pvu_from, puu_from, x_from, step;
      if (i + 1 <= j - 1) {
        pvu_from = k.Pvu(i + 1, j - 1);
        puu_from = k.Puu(i + 1, j - 1);
        x_from = x + h;
        step = h;
      } else {  // odd sum: start at the diagonal point x = xi = (i + 1/2) h
        x_from = x + 0.5 * h;
        pvu_from = pvu_diag(x_from);
        puu_from = puu_diag(x_from);
        step = 0.5 * h;
      }
      const double c2 = pvu_from - 0.5 * step * b(x_from) * puu_from;
      const double d2 = 0.5 * step * b(x);
      double puu, pvu;
      if (i == 0) {
        // (10.2.16): Puu = -Pvu, so Pvu = c2 + d2 Pvu.
        pvu = c2 / (1.0 - d2);
        puu = -pvu;
      } else {
        // P^uu along the diagonal from (i-1, j-1): Puu = c1 - d1 Pvu.
        const double c1 = k.Puu(i - 1, j - 1) - 0.5 * h * a(x - h) * k.Pvu(i - 1, j - 1);
        const double d1 = 0.5 * h * a(x);
        puu = (c1 - d1 * c2) / (1.0 - d1 * d2);
        pvu = c2 - d2 * puu;
      }
      k.puu_[k.Index(i, j)] = puu;
      k.pvu_[k.Index(i, j)] = pvu;
    }
  }
  return k;
}

}  // namespace mpdrig::observer
