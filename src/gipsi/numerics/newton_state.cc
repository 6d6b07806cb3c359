/// @file
/// NewtonSolver checkpoints: the warm start of the next Solve's first linear solve (it changes
/// the iterates of iterative linear solvers), and with reuse_factorization the factorisation
/// kept for the next Solve, saved as the values of the matrix that was factorised and
/// factorised again on restore, with the Anderson history that belongs to it. Bitwise
/// continuation needs all of them.
///
/// The factorised values are those of J: while a factorisation is kept (factor_valid_), Solve
/// writes J only in CalcResidualAndJacobian, and it marks the factors stale whenever it does so
/// without factorising (when the iterations run out), so the saved J is always the factorised
/// matrix. Whether the linear solver was switched to its indefinite mode is not saved: the
/// switch happens at the first factorisation that needs it, in the resumed run as in the
/// original, and gives the same factors.

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "gipsi/base/state.h"
#include "gipsi/numerics/newton.h"

namespace gipsi {

void NewtonSolver::SaveState(StateWriter& out, const SparseMatrix& J) const {
  out.BeginSection("NewtonSolver", 4);
  out.WriteBool(warm_valid_);
  out.WriteMatrix(warm_);
  const bool keep = options_.reuse_factorization && factor_valid_;
  out.WriteBool(keep);
  if (keep) {
    out.WriteArray(std::span<const double>(J.valuePtr(), static_cast<std::size_t>(J.nonZeros())));
    // The low-rank vectors kept with it (bordered unknowns); J⁻¹ b is solved again on restore.
    out.WriteBool(low_rank_kept_);
    if (low_rank_kept_) {
      out.WriteInt(static_cast<std::int64_t>(low_rank_b_.size()));
      for (const VecX& b : low_rank_b_) out.WriteMatrix(b);
    }
    // The Anderson history kept with it (NewtonOptions::anderson): the next Solve starts from
    // it.
    out.WriteInt(aa_count_);
    if (aa_count_ > 0) {
      out.WriteInt(aa_head_);
      out.WriteMatrix(aa_dx_);
      out.WriteMatrix(aa_df_);
    }
  }
  linear_->SaveState(out);  // the serial solvers write nothing
  out.EndSection();
}

void NewtonSolver::RestoreState(StateReader& in, SparseMatrix& J) {
  in.BeginSection("NewtonSolver", 4);
  warm_valid_ = in.ReadBool();
  in.ReadMatrixExact(warm_, "the warm start of the Newton solver");
  factor_valid_ = false;
  low_rank_kept_ = false;
  ClearAnderson();
  if (in.ReadBool()) {
    if (!options_.reuse_factorization)
      in.Fail("the checkpoint keeps a Newton factorisation but this scene does not reuse them");
    std::vector<double> values(static_cast<std::size_t>(J.nonZeros()));
    in.ReadArrayExact(values, "the factorised Newton matrix");
    std::copy(values.begin(), values.end(), J.valuePtr());
    // The run that saved it may have switched its solver to the indefinite mode (newton.cc).
    NewtonStats stats;
    if (!FactorizeTangent(J, stats)) in.Fail("the saved Newton matrix cannot be factorised again");
    factor_valid_ = true;
    if (in.ReadBool()) {
      const std::int64_t terms = in.ReadInt();
      if (terms < 0 || terms > kMaxLowRankTerms)
        in.Fail("more low-rank terms than a Newton solver takes");
      const auto count = static_cast<std::size_t>(terms);
      low_rank_b_.resize(count);
      if (low_rank_z_.size() < count) low_rank_z_.resize(count);
      for (std::size_t k = 0; k < count; ++k) {
        low_rank_b_[k].setZero(sparse_size_);
        in.ReadMatrixExact(low_rank_b_[k], "a low-rank vector of the Newton solver");
        if (!SolveLowRankZ(low_rank_b_[k], low_rank_z_[k], stats))
          in.Fail("the saved Newton low-rank vectors cannot be solved again");
      }
      low_rank_kept_ = true;
    }
    const std::int64_t count = in.ReadInt();
    if (count < 0 || count > options_.anderson)
      in.Fail("the checkpoint keeps a longer Anderson history than this scene's \"anderson\"");
    if (count > 0) {
      const std::int64_t head = in.ReadInt();
      if (head < 0 || head >= options_.anderson) in.Fail("a corrupted Anderson history");
      in.ReadMatrixExact(aa_dx_, "the Newton solver's Anderson history");
      in.ReadMatrixExact(aa_df_, "the Newton solver's Anderson history");
      aa_head_ = static_cast<int>(head);
    }
    aa_count_ = static_cast<int>(count);
  }
  linear_->RestoreState(in, J);
  in.EndSection();
}

}  // namespace gipsi
