// The implicit route to the elastic tensor: the bond forces and moments of the DEM bond loop
// (libs/dem/src/bond_kernel.hpp), linearised exactly about the current state, assembled into a
// sparse stiffness matrix with six DOF per particle, and solved with Eigen for six macroscopic
// strain cases imposed through the bond vectors (affine ε·d plus periodic fluctuations). Solvers:
// Eigen's SimplicialLDLT, or conjugate gradients preconditioned by smoothed-aggregation multigrid
// whose coarse spaces carry the particles' rigid-body modes (tomodem/linalg/amg.hpp).
#include <omp.h>

#include <Eigen/Dense>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <tuple>

#include "tomodem/linalg/amg.hpp"
#include "tomodem/linalg/petsc_solver.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/mechanics/elastic.hpp"
#include "bond_rows.hpp"

namespace tomodem::mechanics {

using detail::bond_rows;
using detail::Row;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

using SpMatR = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

}  // namespace

void uniaxial_from_tensor(const Matrix6& C, int axis, double& E, double& nu) {
  Eigen::Matrix3d cn;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) cn(a, b) = C[a][b];
  const Eigen::Matrix3d S = cn.inverse();
  E = 1 / S(axis, axis);
  const int b = (axis + 1) % 3, c = (axis + 2) % 3;
  nu = -0.5 * (S(b, axis) + S(c, axis)) / S(axis, axis);
}

struct StiffnessSystem::Impl {
  const Packing& p;
  const std::vector<Image>& image;
  ImplicitOptions o;
  ImplicitResult info;
  std::vector<int64_t> pid;               // particle -> index in the load-bearing cluster (−1: left out)
  int64_t np = 0;
  std::vector<std::size_t> used;          // bonds of the cluster
  double rs = 0, V = 0;
  std::vector<std::vector<int64_t>> nbr;  // block pattern: sorted bonded particles and the particle itself
  std::vector<int64_t> bstart;
  std::vector<int64_t> dof;               // (particle in cluster)·6 + component -> unknown (−1: pinned or dropped)
  int64_t ndof = 0;
  BondStiffnesses k;
  // The particles [a0, a1) and their unknowns [r0, r1) are the rows this process assembles: all of
  // them, or with PETSc on several ranks the rank's own (PetscSolver::owned_nodes), so that no
  // rank holds the whole matrix (bonds across two ranks are assembled by both, each its rows).
  int64_t a0 = 0, a1 = 0, r0 = 0, r1 = 0;
  SpMatR K;                               // rows [r0, r1), columns all unknowns
  Eigen::MatrixXd f;                      // right-hand side per unit strain ((r1 − r0) × 6)
  double shift = 0;
  ElasticSolver kind = ElasticSolver::ldlt;  // never automatic
  long cap = 0;
  std::unique_ptr<Amg> amg;
  std::unique_ptr<PetscSolver> petsc;     // MPI build: PETSc CG + GAMG (docs/solvers.md)
  std::unique_ptr<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double, Eigen::ColMajor, int>, Eigen::Lower>> ldlt;
  std::unique_ptr<Eigen::ConjugateGradient<SpMatR, Eigen::Lower | Eigen::Upper, Eigen::IncompleteCholesky<double>>> ic;

  Impl(const Packing& pk, const std::vector<Image>& im) : p(pk), image(im) {}

  double tension(std::size_t b, const Vec3& d) const {
    const double L = norm(d);
    if (std::abs(L - p.bonds.rest_length[b]) <= 1e-12 * L) return 0;  // round-off of the stored rest length
    return k.kn[b] * (L - p.bonds.rest_length[b]);
  }
  int rows_of(std::size_t b, Row* rows) const {
    const Vec3 d = bond_vector(p, image[b], b);
    return bond_rows(d, p.particles.radius[p.bonds.i[b]], p.particles.radius[p.bonds.j[b]], rs, k.kn[b], k.kt[b],
                     k.ktwist[b], k.kbend[b], tension(b, d), rows);
  }
  CsrView view() const { return {int32_t(K.rows()), K.outerIndexPtr(), K.innerIndexPtr(), K.valuePtr()}; }
  bool owned(int64_t a) const { return a >= a0 && a < a1; }

  /// Blocks and right-hand sides from the bond rows; on the first call also the DOF map.
  void assemble(bool first);
  /// Factorisation (ldlt), preconditioner (amg, cg-ic, petsc).
  void prepare(bool first);
  /// The unknowns' particles and kinds, positions and rotation scale: the rigid-body modes.
  NearNullspace near_nullspace() const;
  /// auto: a Jacobi-CG trial on the first strain case before the chosen path's set-up (below).
  void trial();
  Eigen::VectorXd trial_q;                 // the trial's solution of the unit strain case xx (kept if cg wins)
  int trial_iterations = 0;
};

/// The cost model is fitted on disordered networks; on a perfect lattice Jacobi CG converges in a
/// fraction of the predicted iterations and is up to 4× faster than the path the model picks
/// (docs/young.md). So before the chosen path's set-up, Jacobi CG runs the first strain case with
/// the iterations that the chosen path's predicted time per case buys at CG's predicted rate:
/// budget = (t_chosen / cases) / (t_cg / (cases · it_cg)) = it_cg · t_chosen / t_cg. Converged
/// within it: CG is taken (its whole run then costs about what the chosen path was predicted to,
/// or less) and the trial's solution serves the first case; otherwise the chosen path runs and
/// the trial cost at most 1/cases of its predicted time (1/3 with --no-tensor, 1/6 for the tensor).
void StiffnessSystem::Impl::trial() {
  const SolverCosts& c = info.predicted;
  const double chosen_s = kind == ElasticSolver::ldlt ? c.ldlt_s : c.amg_s;
  if (!(c.cg_s > 0) || !(chosen_s > 0)) return;
  const long budget = std::min<long>(cap, long(c.cg_iterations * chosen_s / c.cg_s));
  if (budget < 10 || f.cols() == 0 || f.col(0).norm() == 0) return;  // too few iterations to converge
  const auto t0 = Clock::now();
  const Eigen::VectorXd rhs = f.col(0);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(ndof);
  const PcgReport r = pcg(view(), nullptr, rhs.data(), q.data(), o.tolerance, int(budget));
  info.setup_s += seconds_since(t0);
  tomodem::info("  auto: Jacobi-CG trial on strain case 1: " + std::to_string(r.iterations) + " of " + std::to_string(budget) +
       " iterations, " + (r.converged ? "converged: cg" : std::string("not converged: ") + to_string(kind)));
  if (!r.converged) return;
  kind = ElasticSolver::cg;
  info.solver = kind;
  trial_q = std::move(q);
  trial_iterations = r.iterations;
}

void StiffnessSystem::Impl::assemble(bool first) {
  // The 6×6 blocks of the owned particles' block rows only.
  std::vector<double> blocks(std::size_t(bstart[a1] - bstart[a0]) * 36, 0.0);
  auto block = [&](int64_t a, int64_t c) -> double* {
    const auto it = std::lower_bound(nbr[a].begin(), nbr[a].end(), c);
    return &blocks[std::size_t(bstart[a] - bstart[a0] + (it - nbr[a].begin())) * 36];
  };
  Eigen::MatrixXd F = Eigen::MatrixXd::Zero((a1 - a0) * 6, 6);
  // On the first call the diagonal of every particle (cheap: 6 numbers each), for the DOF map,
  // which every rank needs whole; summed in the order the blocks sum it, so it is the same.
  std::vector<double> diag(first ? std::size_t(np) * 6 : 0, 0.0);
  Row rows[8];
  long prestressed = 0;
  for (std::size_t b : used) {
    const int64_t ends[2] = {pid[p.bonds.i[b]], pid[p.bonds.j[b]]};
    const bool mine[2] = {owned(ends[0]), owned(ends[1])};
    prestressed += tension(b, bond_vector(p, image[b], b)) != 0;
    if (!first && !mine[0] && !mine[1]) continue;
    const int nr = rows_of(b, rows);
    for (int r = 0; r < nr; ++r) {
      const Row& w = rows[r];
      for (int ea = 0; ea < 2; ++ea)
        for (int eb = 0; eb < 2; ++eb) {
          if (first && ends[ea] == ends[eb])
            for (int x = 0; x < 6; ++x) diag[std::size_t(ends[ea] * 6 + x)] += w.k * w.g[6 * ea + x] * w.g[6 * eb + x];
          if (!mine[ea]) continue;
          double* B = block(ends[ea], ends[eb]);
          for (int x = 0; x < 6; ++x) {
            const double gx = w.k * w.g[6 * ea + x];
            if (gx == 0) continue;
            for (int y = 0; y < 6; ++y) B[6 * x + y] += gx * w.g[6 * eb + y];
          }
        }
      for (int ea = 0; ea < 2; ++ea)
        for (int x = 0; x < 6 && mine[ea]; ++x)
          for (int c = 0; c < 6; ++c) F((ends[ea] - a0) * 6 + x, c) -= w.k * w.g[6 * ea + x] * w.a[c];
    }
  }
  info.prestress_bonds = double(prestressed);
  if (first) {
    // Active DOFs: the first particle's translations are pinned (rigid translations), and DOFs
    // without stiffness (rotations of particles whose bonds carry no moments) are left out.
    double diag_sum = 0;
    long diag_n = 0;
    for (int64_t a = 0; a < np; ++a)
      for (int x = 0; x < 6; ++x)
        if (diag[std::size_t(a * 6 + x)] > 0) diag_sum += diag[std::size_t(a * 6 + x)], ++diag_n;
    const double diag_mean = diag_sum / double(std::max(1L, diag_n));
    dof.assign(std::size_t(np) * 6, -1);
    ndof = 0;
    for (int64_t a = 0; a < np; ++a) {
      if (a == a0) r0 = ndof;
      if (a == a1) r1 = ndof;
      for (int x = 0; x < 6; ++x) {
        if (a == 0 && x < 3) continue;
        if (diag[std::size_t(a * 6 + x)] > 1e-13 * diag_mean) dof[a * 6 + x] = ndof++;
      }
    }
    if (a0 == np) r0 = ndof;
    if (a1 == np) r1 = ndof;
    // A tiny shift keeps the direct factorisation regular in mechanisms that the load does not
    // excite (e.g. the floppy shear of a lattice with normal bonds only); its relative effect on
    // loaded modes is below 1e-12 times the condition number's share (docs/young.md). Added to
    // LDLT's copy of K only: K itself is the unshifted stiffness for every path.
    shift = 1e-12 * diag_mean;
  }
  K = SpMatR(r1 - r0, ndof);
  Eigen::VectorXi per_row(r1 - r0);
  for (int64_t a = a0; a < a1; ++a)
    for (int x = 0; x < 6; ++x) {
      const int64_t r = dof[a * 6 + x];
      if (r < 0) continue;
      int64_t cnt = 0;
      for (int64_t c : nbr[a])
        for (int y = 0; y < 6; ++y) cnt += dof[c * 6 + y] >= 0;
      per_row[r - r0] = int(cnt);
    }
  K.reserve(per_row);
  for (int64_t a = a0; a < a1; ++a)
    for (int x = 0; x < 6; ++x) {
      const int64_t r = dof[a * 6 + x];
      if (r < 0) continue;
      for (std::size_t e = 0; e < nbr[a].size(); ++e) {
        const int64_t c = nbr[a][e];
        const double* B = &blocks[std::size_t(bstart[a] - bstart[a0] + int64_t(e)) * 36];
        for (int y = 0; y < 6; ++y) {
          const int64_t col = dof[c * 6 + y];
          if (col >= 0) K.insert(int(r - r0), int(col)) = B[6 * x + y];
        }
      }
    }
  K.makeCompressed();
  f.resize(r1 - r0, 6);
  for (int64_t a = a0 * 6; a < a1 * 6; ++a)
    if (dof[a] >= 0) f.row(dof[a] - r0) = F.row(a - a0 * 6);
}

void StiffnessSystem::Impl::prepare(bool first) {
  const auto t0 = Clock::now();
  if (kind == ElasticSolver::ldlt) {
    Eigen::SparseMatrix<double, Eigen::ColMajor, int> Ks(K);
    for (int64_t r = 0; r < ndof; ++r) Ks.coeffRef(int(r), int(r)) += shift;
    ldlt = std::make_unique<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double, Eigen::ColMajor, int>, Eigen::Lower>>(Ks);
    if (ldlt->info() != Eigen::Success) throw RuntimeFailure("stiffness matrix: LDLT factorisation failed");
    const auto& L = ldlt->matrixL().nestedExpression();  // the factor's columns: what the cost model predicts
    info.factor_nonzeros = info.factor_flops = 0;
    for (Eigen::Index j = 0; j < L.outerSize(); ++j) {
      const double cj = double(L.outerIndexPtr()[j + 1] - L.outerIndexPtr()[j]);
      info.factor_nonzeros += cj;
      info.factor_flops += cj * cj;
    }
  } else if (kind == ElasticSolver::petsc) {
    if (first) {
      PetscSolveOptions po;
      po.tolerance = o.tolerance;
      po.max_iterations = int(cap);
      petsc = std::make_unique<PetscSolver>(view(), PetscRows{int32_t(ndof), int32_t(r0)}, near_nullspace(), po);
      info.levels = petsc->stats().levels;
    } else {
      petsc->replace_matrix(view());
    }
  } else if (kind == ElasticSolver::amg) {
    if (first) {
      const NearNullspace ns = near_nullspace();
      AmgOptions ao;
      ao.strength = 0;         // every bond couples (the rotational coupling is weak but matters)
      ao.aggregate_radius = 2; // low coordination (Z ≈ 4): radius-1 aggregates would coarsen by ~5 only
      amg = std::make_unique<Amg>(view(), ns, ao);
      info.levels = int(amg->stats().rows.size());
      info.operator_complexity = amg->stats().operator_complexity;
    } else {
      amg->replace_finest(view());
    }
  } else if (kind == ElasticSolver::cg_ic) {
    ic = std::make_unique<Eigen::ConjugateGradient<SpMatR, Eigen::Lower | Eigen::Upper, Eigen::IncompleteCholesky<double>>>();
    ic->setTolerance(o.tolerance);
    ic->setMaxIterations(cap);
    ic->compute(K);
    if (ic->info() != Eigen::Success) throw RuntimeFailure("stiffness matrix: incomplete Cholesky failed");
  }
  info.setup_s += seconds_since(t0);
}

NearNullspace StiffnessSystem::Impl::near_nullspace() const {
  NearNullspace ns;
  ns.node.resize(std::size_t(ndof));
  ns.kind.resize(std::size_t(ndof));
  for (int64_t a = 0; a < np * 6; ++a)
    if (dof[a] >= 0) {
      ns.node[std::size_t(dof[a])] = int32_t(a / 6);
      ns.kind[std::size_t(dof[a])] = int8_t(a % 6);
    }
  ns.position.resize(std::size_t(np));
  for (std::size_t i = 0; i < pid.size(); ++i)
    if (pid[i] >= 0) ns.position[std::size_t(pid[i])] = p.particles.position[i];
  ns.rotation_scale = rs;
  ns.cell = p.cell.h;
  for (int c = 0; c < 3; ++c) ns.periodic[c] = p.cell.periodic[c];
  return ns;
}

StiffnessSystem::StiffnessSystem(const Packing& p, const std::vector<Image>& image, const BondStiffnesses& k,
                                 const ImplicitOptions& o, const std::string& file)
    : impl_(std::make_unique<Impl>(p, image)) {
  const auto t0 = Clock::now();
  Impl& m = *impl_;
  m.o = o;
  m.k = k;
  if (!(p.cell.periodic[0] && p.cell.periodic[1] && p.cell.periodic[2]))
    throw InputError(file, "/cell/periodic", "not periodic in x, y and z",
                     "the elastic tensor is computed on a periodic cell");
  long intact = 0;
  for (uint8_t s : p.bonds.state) intact += s == BondTable::intact;
  if (intact == 0)
    throw InputError(file, "/bonds", std::to_string(p.bonds.size()) + " bonds, 0 intact",
                     "a bonded network is needed (run tomodem-bond first)");
  const Clusters cl = find_clusters(p, image);
  if (cl.main < 0 || cl.wrap_rank[cl.main] < 3)
    throw InputError(file, "/bonds", "largest cluster " + std::to_string(cl.main >= 0 ? cl.size[cl.main] : 0) +
                                         " particles, wraps along " +
                                         std::to_string(cl.main >= 0 ? cl.wrap_rank[cl.main] : 0) + " directions",
                     "no bonded cluster spans the periodic cell in three directions");
  // Particles of the load-bearing cluster.
  const std::size_t np_all = p.particles.size();
  m.pid.assign(np_all, -1);
  double rsum = 0;
  for (std::size_t i = 0; i < np_all; ++i)
    if (cl.label[i] == cl.main) {
      m.pid[i] = m.np++;
      rsum += p.particles.radius[i];
    }
  m.rs = rsum / double(m.np);
  for (std::size_t b = 0; b < p.bonds.size(); ++b)
    if (p.bonds.state[b] == BondTable::intact && m.pid[p.bonds.i[b]] >= 0) m.used.push_back(b);
  m.info.particles_used = m.np;
  m.info.particles_removed = long(np_all) - m.np;
  m.info.bonds_used = long(m.used.size());
  m.info.bonds_removed = intact - long(m.used.size());
  m.V = p.cell.volume();
  m.nbr.resize(std::size_t(m.np));
  for (int64_t a = 0; a < m.np; ++a) m.nbr[a].push_back(a);
  for (std::size_t b : m.used) {
    const int64_t a = m.pid[p.bonds.i[b]], c = m.pid[p.bonds.j[b]];
    m.nbr[a].push_back(c);
    m.nbr[c].push_back(a);
  }
  m.bstart.assign(std::size_t(m.np) + 1, 0);
  for (int64_t a = 0; a < m.np; ++a) {
    std::sort(m.nbr[a].begin(), m.nbr[a].end());
    m.nbr[a].erase(std::unique(m.nbr[a].begin(), m.nbr[a].end()), m.nbr[a].end());
    m.bstart[a + 1] = m.bstart[a] + int64_t(m.nbr[a].size());
  }
  // The cost model sees the matrix before assembly: 6 unknowns per particle, 3 when no bond carries
  // moments (the rotations are dropped then), and 36 or 9 entries per block of the pattern.
  bool moments = false;
  for (std::size_t b : m.used) moments = moments || k.kt[b] > 0 || k.ktwist[b] > 0 || k.kbend[b] > 0;
  const int per = moments ? 6 : 3;
  m.info.predicted = predict_solver_costs(m.nbr, long(per) * m.np, double(per * per) * double(m.bstart[m.np]),
                                          o.full_tensor ? 6 : 3, o.tolerance);
  m.kind = o.solver == ElasticSolver::automatic ? m.info.predicted.cheapest : o.solver;
  m.info.solver = m.kind;
  m.a1 = m.np;
  if (m.kind == ElasticSolver::petsc) std::tie(m.a0, m.a1) = PetscSolver::owned_nodes(int32_t(m.np));
  m.assemble(true);
  m.info.dofs = m.ndof;
  m.cap = o.max_iterations > 0 ? o.max_iterations
                               : int(std::max<long>(1000, long(20 * 100 * std::cbrt(double(m.ndof)))));
  m.info.assembly_s = seconds_since(t0);
  if (o.solver == ElasticSolver::automatic && m.kind != ElasticSolver::cg) m.trial();
  m.prepare(true);
}

StiffnessSystem::~StiffnessSystem() = default;

const ImplicitResult& StiffnessSystem::summary() const { return impl_->info; }

void StiffnessSystem::update_stiffnesses(const BondStiffnesses& k) {
  Impl& m = *impl_;
  if (k.kn.size() != m.k.kn.size() || k.kt.size() != m.k.kt.size() || k.ktwist.size() != m.k.ktwist.size() ||
      k.kbend.size() != m.k.kbend.size())
    throw RuntimeFailure("stiffness system: the new stiffnesses are for another set of bonds");
  m.k = k;
  m.trial_q.resize(0);  // the trial's solution was for the old stiffnesses
  m.assemble(false);
  m.prepare(false);
}

LinearResponse StiffnessSystem::solve(const std::array<double, 6>& strain) const {
  const Impl& m = *impl_;
  LinearResponse out;
  const Eigen::Map<const Eigen::Matrix<double, 6, 1>> eps(strain.data());
  const Eigen::VectorXd rhs = m.f * eps;
  Eigen::VectorXd q = Eigen::VectorXd::Zero(m.ndof);
  const double fn = rhs.norm();
  if (m.kind == ElasticSolver::petsc) {
    // Collective on every rank (rhs holds the rank's rows; a rank's part may be zero): the whole
    // solution comes back, and the residual over all ranks.
    const PcgReport r = m.petsc->solve(rhs.data(), q.data());
    out.iterations = r.iterations;
    out.residual = r.residual;
    out.converged = r.converged;
  } else if (fn > 0) {
    if (m.kind == ElasticSolver::ldlt) {
      q = m.ldlt->solve(rhs);
    } else if (m.kind == ElasticSolver::cg_ic) {
      q = m.ic->solve(rhs);
      out.iterations = m.ic->iterations();
    } else if (m.trial_q.size() > 0 && strain == std::array<double, 6>{1, 0, 0, 0, 0, 0}) {
      q = m.trial_q;  // auto's Jacobi-CG trial solved this case already, to the same tolerance
      out.iterations = m.trial_iterations;
    } else {
      const PcgReport r = pcg(m.view(), m.amg.get(), rhs.data(), q.data(), m.o.tolerance, int(m.cap));
      out.iterations = r.iterations;
      out.converged = r.converged;
    }
    out.residual = (rhs - m.K * q).norm() / fn;
  }
  // Bond deformations e = g·q + a·ε; stress (1/V) Σ k e a; the bond loop's forces and moments.
  const std::size_t nb = m.p.bonds.size();
  out.normal_force.assign(nb, 0.0);
  out.shear_force.assign(nb, 0.0);
  out.twist_moment.assign(nb, 0.0);
  out.bend_moment.assign(nb, 0.0);
  out.force.assign(nb, Vec3{});
  out.fluctuation.assign(m.pid.size(), Vec3{});
  for (std::size_t i = 0; i < m.pid.size(); ++i)
    for (int x = 0; m.pid[i] >= 0 && x < 3; ++x) {
      const int64_t g = m.dof[m.pid[i] * 6 + x];
      if (g >= 0) out.fluctuation[i][x] = q[g];
    }
  Eigen::Matrix<double, 6, 1> sigma = Eigen::Matrix<double, 6, 1>::Zero();
  Row rows[8];
  for (std::size_t b : m.used) {
    const int nr = m.rows_of(b, rows);
    const int64_t ends[2] = {m.pid[m.p.bonds.i[b]], m.pid[m.p.bonds.j[b]]};
    double shear2 = 0, bend2 = 0;
    for (int r = 0; r < nr; ++r) {
      const Row& w = rows[r];
      double e = 0;
      for (int ea = 0; ea < 2; ++ea)
        for (int x = 0; x < 6; ++x) {
          const int64_t g = m.dof[ends[ea] * 6 + x];
          if (g >= 0) e += w.g[6 * ea + x] * q[g];
        }
      for (int x = 0; x < 6; ++x) e += w.a[x] * strain[x];
      const double force = w.k * e;
      for (int x = 0; x < 6; ++x) sigma[x] += force * w.a[x];
      if (w.kind != Row::twist && w.kind != Row::bend)  // translational rows: force along their direction
        out.force[b] -= force * Vec3{w.g[6], w.g[7], w.g[8]};
      switch (w.kind) {
        case Row::normal: out.normal_force[b] = force; break;
        case Row::shear: shear2 += force * force; break;
        case Row::twist: out.twist_moment[b] = force; break;
        case Row::bend: bend2 += force * force; break;
        case Row::prestress: break;
      }
    }
    out.shear_force[b] = std::sqrt(shear2);
    out.bend_moment[b] = std::sqrt(bend2);
  }
  for (int x = 0; x < 6; ++x) out.stress[x] = sigma[x] / m.V;
  return out;
}

ImplicitResult solve_implicit(const Packing& p, const std::vector<Image>& image, const BondStiffnesses& k,
                              const ImplicitOptions& o, const std::string& file) {
  const auto t0 = Clock::now();
  const StiffnessSystem sys(p, image, k, o, file);
  ImplicitResult res = sys.summary();
  res.full_tensor = o.full_tensor;
  const int ncase = o.full_tensor ? 6 : 3;
  const auto t1 = Clock::now();
  Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
  for (int c = 0; c < ncase; ++c) {
    std::array<double, 6> unit{};
    unit[c] = 1;
    const LinearResponse r = sys.solve(unit);
    for (int x = 0; x < 6; ++x) C(x, c) = r.stress[x];
    res.iterations += r.iterations;
    res.residual = std::max(res.residual, r.residual);
    res.converged = res.converged && r.converged;
    if (res.solver != ElasticSolver::ldlt)
      info("  strain case " + std::to_string(c + 1) + "/" + std::to_string(ncase) + ": " +
           std::to_string(r.iterations) + " iterations, residual " + value_text(r.residual));
  }
  res.solve_s = seconds_since(t1);
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) res.C[a][b] = b < ncase ? C(a, b) : std::nan("");
  // Symmetrise the computed block (the exact tensor is symmetric; the difference is the solve error).
  for (int a = 0; a < ncase; ++a)
    for (int b = a + 1; b < ncase; ++b) res.C[a][b] = res.C[b][a] = 0.5 * (C(a, b) + C(b, a));
  for (int ax = 0; ax < 3; ++ax) uniaxial_from_tensor(res.C, ax, res.E_axes[ax], res.nu_axes[ax]);
  res.E = res.E_axes[o.axis];
  res.nu = res.nu_axes[o.axis];
  // E_error: the largest relative residual. Measured against LDLT, the true error of E was 0.1–0.2 ×
  // this number on random networks (docs/young.md); an energy-norm estimate from Jacobi-weighted
  // residuals was optimistic by 40–300× and is not used.
  res.E_error = res.residual;
  // A solve stopped by its iteration cap (--max-iterations, or PETSC_OPTIONS' -ksp_max_it) still
  // gives numbers; E_error carries its residual, and the user is told.
  if (!res.converged)
    warn("the linear solve stopped before its tolerance " + value_text(o.tolerance) + " (largest residual " +
         value_text(res.residual) + " after " + std::to_string(res.iterations) +
         " iterations): E and nu are unconverged; E_error reports the residual (summary: converged false)");
  res.wall_time_s = seconds_since(t0);
  return res;
}

}  // namespace tomodem::mechanics
