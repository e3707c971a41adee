// Runtime benchmark: aggsym's generated C against Pinocchio C++ (the `pin` wheel), same states, same process.
//
//   pinocchio_bench SECONDS STATES CALLS OUT.json NAME URDF [NAME URDF ...]
//
// For each robot: the Pinocchio fixed-base model of the URDF (pinocchio::urdf::buildModel(path, model)); the
// joint order is checked against the generated code's coordinates; STATES random states (q uniform in
// [-pi, pi], qd, qdd, tau standard normal; continuous joints get (cos, sin) in Pinocchio's q) are precomputed.
// First both sides are evaluated on the first few states and compared (relative error per pair); then each
// pair is timed in interleaved batches (one batch = CALLS calls on consecutive states, cycling through the
// STATES; a generated batch, then a Pinocchio batch on the same states, repeated for about SECONDS), and the
// median of the per-batch means is reported in ns per call, wall clock and thread CPU time.  crba and aba are
// timed in both of Pinocchio's conventions (LOCAL, its default, and WORLD) and the faster one is reported.  Batches are short
// (tens of microseconds) so that most hold no preemption on a shared machine and the median ignores those that
// do.
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/parsers/urdf.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "bench.h"

namespace {

const int CHECK_STATES = 5;
const char *const PAIRS[] = {"inertia", "nonlinear_effects", "inverse_dynamics", "forward_dynamics",
                             "inertia_inverse"};
const char *const PINOCCHIO[] = {"crba", "nonLinearEffects", "rnea", "aba", "computeMinverse"};
const int NPAIRS = 5;
// crba and aba take a convention (default LOCAL); both are timed and the faster one is Pinocchio's time.
const int NVARIANTS[] = {2, 1, 1, 2, 1};
const char *const VARIANT[][2] = {{"LOCAL", "WORLD"}, {"", ""}, {"", ""}, {"LOCAL", "WORLD"}, {"", ""}};

struct States {
  int count = 0, nq = 0;
  std::vector<double> q, qd, qdd, tau;       // ours, count x nq
  std::vector<Eigen::VectorXd> Q, V, Vd, T;  // Pinocchio's
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double quantile(std::vector<double> v, double f) {
  std::sort(v.begin(), v.end());
  return v[(size_t)std::floor(f * (double)(v.size() - 1) + 0.5)];
}

double relative_error(const double *ours, const double *theirs, int n) {
  double diff = 0.0, scale = 0.0;
  for (int i = 0; i < n; ++i) {
    diff = std::max(diff, std::fabs(ours[i] - theirs[i]));
    scale = std::max(scale, std::fabs(theirs[i]));
  }
  return diff / std::max(scale, 1e-300);
}

// Row-major full matrix from Pinocchio's upper triangle (crba and computeMinverse fill only that).
template <typename M>
std::vector<double> symmetric_from_upper(const M &m) {
  const int n = (int)m.rows();
  std::vector<double> out((size_t)n * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) out[(size_t)i * n + j] = i <= j ? m(i, j) : m(j, i);
  return out;
}

std::string json_escape(const std::string &s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out;
}

}  // namespace

int main(int argc, char **argv) {
  if (argc < 7 || (argc - 5) % 2) {
    std::fprintf(stderr, "usage: %s SECONDS STATES CALLS OUT.json NAME URDF [NAME URDF ...]\n", argv[0]);
    return 2;
  }
  const double seconds = std::atof(argv[1]);
  const int nstates = std::atoi(argv[2]);
  const int calls = std::atoi(argv[3]);
  FILE *out = std::fopen(argv[4], "w");
  if (!out || nstates < 1 || calls < 1) {
    std::fprintf(stderr, "cannot write %s, or STATES/CALLS < 1\n", argv[4]);
    return 2;
  }
  std::fprintf(out, "{\"seconds_per_pair\": %g, \"states\": %d, \"calls_per_batch\": %d, \"robots\": [", seconds,
               nstates, calls);
  for (int r = 5; r < argc; r += 2) {
    const std::string name = argv[r], path = argv[r + 1];
    const bench_model *bm = nullptr;
    for (int k = 0; bench_models[k]; ++k)
      if (name == bench_models[k]->name) bm = bench_models[k];
    if (!bm) {
      std::fprintf(stderr, "no generated model %s linked in\n", name.c_str());
      return 2;
    }
    pinocchio::Model model;
    pinocchio::urdf::buildModel(path, model);
    pinocchio::Data data(model);
    const int n = bm->nq;
    if (model.nv != n) {
      std::fprintf(stderr, "%s: Pinocchio nv = %d, generated nq = %d\n", name.c_str(), (int)model.nv, n);
      return 1;
    }
    // The generated coordinates must be Pinocchio's joints in the same order.
    std::vector<int> continuous(n, 0);
    for (pinocchio::JointIndex j = 1; j < (pinocchio::JointIndex)model.njoints; ++j) {
      const auto &joint = model.joints[j];
      for (int k = 0; k < joint.nv(); ++k) {
        const int i = joint.idx_v() + k;
        if (model.names[j] != bm->joints[i]) {
          std::fprintf(stderr, "%s: coordinate %d is joint %s in the generated code, %s in Pinocchio\n",
                       name.c_str(), i, bm->joints[i], model.names[j].c_str());
          return 1;
        }
      }
      if (joint.nq() == 2 && joint.nv() == 1) {
        continuous[joint.idx_v()] = 1;
      } else if (joint.nq() != joint.nv()) {
        std::fprintf(stderr, "%s: joint %s has nq %d, nv %d\n", name.c_str(), model.names[j].c_str(), joint.nq(),
                     joint.nv());
        return 1;
      }
    }
    // States.
    States s;
    s.count = nstates;
    s.nq = n;
    std::mt19937_64 rng(20240611u + (unsigned)r);
    std::uniform_real_distribution<double> angle(-M_PI, M_PI);
    std::normal_distribution<double> normal(0.0, 1.0);
    for (int k = 0; k < nstates; ++k) {
      Eigen::VectorXd Q(model.nq), V(n), Vd(n), T(n);
      for (int i = 0; i < n; ++i) {
        s.q.push_back(angle(rng));
        s.qd.push_back(V[i] = normal(rng));
        s.qdd.push_back(Vd[i] = normal(rng));
        s.tau.push_back(T[i] = normal(rng));
      }
      for (pinocchio::JointIndex j = 1; j < (pinocchio::JointIndex)model.njoints; ++j) {
        const auto &joint = model.joints[j];
        const int iv = joint.idx_v(), iq = joint.idx_q();
        if (continuous[iv]) {
          Q[iq] = std::cos(s.q[(size_t)k * n + iv]);
          Q[iq + 1] = std::sin(s.q[(size_t)k * n + iv]);
        } else {
          for (int i = 0; i < joint.nv(); ++i) Q[iq + i] = s.q[(size_t)k * n + iv + i];
        }
      }
      s.Q.push_back(Q);
      s.V.push_back(V);
      s.Vd.push_back(Vd);
      s.T.push_back(T);
    }
    bench_states cs = {s.count, n, s.q.data(), s.qd.data(), s.qdd.data(), s.tau.data(), bm->p};
    std::vector<double> buf((size_t)n * n);

    // Agreement on the first states.
    double err[NPAIRS] = {0, 0, 0, 0, 0};
    for (int k = 0; k < std::min(CHECK_STATES, nstates); ++k) {
      const double *q = &s.q[(size_t)k * n], *qd = &s.qd[(size_t)k * n];
      const double *qdd = &s.qdd[(size_t)k * n], *tau = &s.tau[(size_t)k * n];
      bm->inertia(q, bm->p, buf.data());
      pinocchio::crba(model, data, s.Q[k], pinocchio::Convention::LOCAL);
      err[0] = std::max(err[0], relative_error(buf.data(), symmetric_from_upper(data.M).data(), n * n));
      pinocchio::crba(model, data, s.Q[k], pinocchio::Convention::WORLD);
      err[0] = std::max(err[0], relative_error(buf.data(), symmetric_from_upper(data.M).data(), n * n));
      bm->nonlinear_effects(q, qd, bm->p, buf.data());
      pinocchio::nonLinearEffects(model, data, s.Q[k], s.V[k]);
      err[1] = std::max(err[1], relative_error(buf.data(), data.nle.data(), n));
      bm->inverse_dynamics(q, qd, qdd, bm->p, buf.data());
      pinocchio::rnea(model, data, s.Q[k], s.V[k], s.Vd[k]);
      err[2] = std::max(err[2], relative_error(buf.data(), data.tau.data(), n));
      bm->forward_dynamics(q, qd, tau, bm->p, buf.data());
      pinocchio::aba(model, data, s.Q[k], s.V[k], s.T[k], pinocchio::Convention::LOCAL);
      err[3] = std::max(err[3], relative_error(buf.data(), data.ddq.data(), n));
      pinocchio::aba(model, data, s.Q[k], s.V[k], s.T[k], pinocchio::Convention::WORLD);
      err[3] = std::max(err[3], relative_error(buf.data(), data.ddq.data(), n));
      bm->inertia_inverse(q, bm->p, buf.data());
      pinocchio::computeMinverse(model, data, s.Q[k]);
      err[4] = std::max(err[4], relative_error(buf.data(), symmetric_from_upper(data.Minv).data(), n * n));
    }

    // Pinocchio's batch timers: the same loop shape as the C ones (bench.h).
    auto batch = [&](int first, double *cpu_ns, auto &&call) {
      double acc = 0.0;
      int i = first;
      const double c0 = bench_cpu_now_ns(), t0 = bench_now_ns();
      for (int k = 0; k < calls; ++k) {
        acc += call(i);
        if (++i == s.count) i = 0;
      }
      const double t1 = bench_now_ns(), c1 = bench_cpu_now_ns();
      bench_sink += acc;
      *cpu_ns = (c1 - c0) / calls;
      return (t1 - t0) / calls;
    };
    using Timer = std::function<double(int, double *)>;
    auto crba_timer = [&](pinocchio::Convention c) -> Timer {
      return [&, c](int first, double *cpu) {
        return batch(first, cpu, [&](int i) {
          pinocchio::crba(model, data, s.Q[i], c);
          return data.M(0, 0);
        });
      };
    };
    auto aba_timer = [&](pinocchio::Convention c) -> Timer {
      return [&, c](int first, double *cpu) {
        return batch(first, cpu, [&](int i) {
          pinocchio::aba(model, data, s.Q[i], s.V[i], s.T[i], c);
          return data.ddq[0];
        });
      };
    };
    Timer pin_timer[NPAIRS][2] = {
        {crba_timer(pinocchio::Convention::LOCAL), crba_timer(pinocchio::Convention::WORLD)},
        {[&](int first, double *cpu) {
           return batch(first, cpu, [&](int i) {
             pinocchio::nonLinearEffects(model, data, s.Q[i], s.V[i]);
             return data.nle[0];
           });
         },
         nullptr},
        {[&](int first, double *cpu) {
           return batch(first, cpu, [&](int i) {
             pinocchio::rnea(model, data, s.Q[i], s.V[i], s.Vd[i]);
             return data.tau[0];
           });
         },
         nullptr},
        {aba_timer(pinocchio::Convention::LOCAL), aba_timer(pinocchio::Convention::WORLD)},
        {[&](int first, double *cpu) {
           return batch(first, cpu, [&](int i) {
             pinocchio::computeMinverse(model, data, s.Q[i]);
             return data.Minv(0, 0);
           });
         },
         nullptr},
    };
    bench_timer ours_timer[NPAIRS] = {bm->t_inertia, bm->t_nonlinear_effects, bm->t_inverse_dynamics,
                                      bm->t_forward_dynamics, bm->t_inertia_inverse};

    std::fprintf(out, "%s{\"name\": \"%s\", \"urdf\": \"%s\", \"nq\": %d, \"pinocchio_nq\": %d, \"pairs\": [",
                 r == 5 ? "" : ", ", json_escape(name).c_str(), json_escape(path).c_str(), n, (int)model.nq);
    for (int k = 0; k < NPAIRS; ++k) {
      const int nv = NVARIANTS[k];
      // warm-up and calibration: once through all states on each side
      double cpu = 0.0, tg = 0.0, tp = 0.0;
      for (int first = 0; first < nstates; first += calls) {
        tg += ours_timer[k](&cs, first, calls, buf.data(), &cpu) * calls;
        for (int v = 0; v < nv; ++v) tp += pin_timer[k][v](first, &cpu) * calls;
      }
      const double per_batch = (tg + tp) / nstates * calls;  // ns for one generated + one Pinocchio batch each
      int batches = (int)std::ceil(seconds * 1e9 / per_batch);
      batches = std::max(51, std::min(batches, 400001));
      std::vector<double> g(batches), gc(batches);
      std::vector<std::vector<double>> p(nv, std::vector<double>(batches)), pc(nv, std::vector<double>(batches));
      for (int b = 0; b < batches; ++b) {
        const int first = (int)(((long long)b * calls) % nstates);
        g[b] = ours_timer[k](&cs, first, calls, buf.data(), &gc[b]);
        for (int v = 0; v < nv; ++v) p[v][b] = pin_timer[k][v](first, &pc[v][b]);
      }
      int best = 0;
      for (int v = 1; v < nv; ++v)
        if (median(p[v]) < median(p[best])) best = v;
      const double mg = median(g), mp = median(p[best]), mgc = median(gc), mpc = median(pc[best]);
      std::string label = PINOCCHIO[k];
      if (nv > 1) label += std::string(" (") + VARIANT[k][best] + ")";
      std::string variants = "{";
      for (int v = 0; v < nv; ++v)
        variants += std::string(v ? ", " : "") + "\"" + (nv > 1 ? VARIANT[k][v] : "default") + "\": " +
                    std::to_string(median(p[v]));
      variants += "}";
      std::fprintf(out,
                   "%s{\"role\": \"%s\", \"pinocchio\": \"%s\", \"batches\": %d, \"generated_ns\": %.3f, "
                   "\"pinocchio_ns\": %.3f, \"ratio\": %.5f, \"generated_ns_q10\": %.3f, \"generated_ns_q90\": %.3f, "
                   "\"pinocchio_ns_q10\": %.3f, \"pinocchio_ns_q90\": %.3f, \"generated_cpu_ns\": %.3f, "
                   "\"pinocchio_cpu_ns\": %.3f, \"cpu_ratio\": %.5f, \"pinocchio_variants_ns\": %s, "
                   "\"check_states\": %d, \"relative_error\": %.3e}",
                   k ? ", " : "", PAIRS[k], label.c_str(), batches, mg, mp, mg / mp, quantile(g, 0.1),
                   quantile(g, 0.9), quantile(p[best], 0.1), quantile(p[best], 0.9), mgc, mpc, mgc / mpc,
                   variants.c_str(), std::min(CHECK_STATES, nstates), err[k]);
      std::fprintf(stderr,
                   "%s %-18s generated %9.1f ns  Pinocchio %-24s %9.1f ns  ratio %.3f  (CPU-time ratio %.3f, "
                   "err %.1e, %d batches of %d)\n",
                   name.c_str(), PAIRS[k], mg, label.c_str(), mp, mg / mp, mgc / mpc, err[k], batches, calls);
    }
    std::fprintf(out, "]}");
    std::fflush(out);
  }
  std::fprintf(out, "], \"sink\": %g}\n", (double)bench_sink);
  std::fclose(out);
  return 0;
}
