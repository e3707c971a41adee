// What the Pinocchio harnesses share (pinocchio_bench.cpp, constrained_derivatives_bench.cpp): random states in
// both sides' coordinates, the joint-order check, the error measure, Pinocchio's batch timer (the loop shape of
// bench.h's C timers) and time_pair, which times one generated routine against Pinocchio's variants in interleaved
// batches and writes the pair's JSON.  Included once per program (its definitions are in an anonymous namespace).
#ifndef AGGSYM_PINOCCHIO_COMMON_HPP
#define AGGSYM_PINOCCHIO_COMMON_HPP

#include <pinocchio/algorithm/constrained-dynamics.hpp>  // RigidConstraintModel
#include <pinocchio/multibody.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "bench.h"

namespace {

const int CHECK_STATES = 5;

struct States {
  int count = 0, nq = 0, nv = 0;
  std::vector<double> q, qd, qdd, tau;       // ours, count x nq (q), count x nv (the others)
  std::vector<Eigen::VectorXd> Q, V, Vd, T;  // Pinocchio's
};

using Timer = std::function<double(int, double *)>;
using ConstraintModels =
    std::vector<pinocchio::RigidConstraintModel, Eigen::aligned_allocator<pinocchio::RigidConstraintModel>>;
using ConstraintDatas =
    std::vector<pinocchio::RigidConstraintData, Eigen::aligned_allocator<pinocchio::RigidConstraintData>>;

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

// Row-major copy of a full matrix (Eigen's are column-major).
template <typename M>
std::vector<double> row_major(const M &m) {
  std::vector<double> out((size_t)m.rows() * m.cols());
  for (int i = 0; i < (int)m.rows(); ++i)
    for (int j = 0; j < (int)m.cols(); ++j) out[(size_t)i * m.cols() + j] = m(i, j);
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

// The generated coordinates must be Pinocchio's joints in the same order; continuous[i] = 1 where coordinate i is
// a continuous joint ((cos, sin) in Pinocchio's q).  A free-flyer root (nq 7, nv 6) is aggsym's quaternion base,
// its seven entries of q the same as Pinocchio's.  False (with a message) when they are not.
bool same_joints(const pinocchio::Model &model, const char *const *joints, const std::string &name,
                 std::vector<int> &continuous) {
  continuous.assign(model.nv, 0);
  for (pinocchio::JointIndex j = 1; j < (pinocchio::JointIndex)model.njoints; ++j) {
    const auto &joint = model.joints[j];
    for (int k = 0; k < joint.nv(); ++k) {
      const int i = joint.idx_v() + k;
      if (model.names[j] != joints[i]) {
        std::fprintf(stderr, "%s: coordinate %d is joint %s in the generated code, %s in Pinocchio\n", name.c_str(),
                     i, joints[i], model.names[j].c_str());
        return false;
      }
    }
    if (joint.nq() == 2 && joint.nv() == 1) {
      continuous[joint.idx_v()] = 1;
    } else if (joint.shortname() == "JointModelFreeFlyer" && j == 1) {
      continue;
    } else if (joint.nq() != joint.nv()) {
      std::fprintf(stderr, "%s: joint %s has nq %d, nv %d\n", name.c_str(), model.names[j].c_str(), joint.nq(),
                   joint.nv());
      return false;
    }
  }
  return true;
}

// Random states: q uniform in [-pi, pi] (a free-flyer's position too, its quaternion a random unit one), qd,
// qdd, tau standard normal; Pinocchio's q from ours.  Our q has nq entries: the free-flyer's seven, then one per
// joint (Pinocchio's q has (cos, sin) for a continuous joint).
States random_states(const pinocchio::Model &model, const std::vector<int> &continuous, int nstates, unsigned seed,
                     bool free_flyer) {
  const int n = (int)model.nv, nq = free_flyer ? n + 1 : n;
  States s;
  s.count = nstates;
  s.nq = nq;
  s.nv = n;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int k = 0; k < nstates; ++k) {
    Eigen::VectorXd Q(model.nq), V(n), Vd(n), T(n);
    for (int i = 0; i < nq; ++i) s.q.push_back(angle(rng));
    if (free_flyer) {  // entries 3..6: a unit quaternion (x, y, z, w)
      double quat[4], norm = 0.0;
      for (double &x : quat) norm += (x = normal(rng)) * x;
      for (int i = 0; i < 4; ++i) s.q[(size_t)k * nq + 3 + i] = quat[i] / std::sqrt(norm);
    }
    for (int i = 0; i < n; ++i) {
      s.qd.push_back(V[i] = normal(rng));
      s.qdd.push_back(Vd[i] = normal(rng));
      s.tau.push_back(T[i] = normal(rng));
    }
    for (pinocchio::JointIndex j = 1; j < (pinocchio::JointIndex)model.njoints; ++j) {
      const auto &joint = model.joints[j];
      const int iv = joint.idx_v(), iq = joint.idx_q(), ours = free_flyer && j > 1 ? iv + 1 : iv;
      if (free_flyer && j == 1) {
        for (int i = 0; i < 7; ++i) Q[iq + i] = s.q[(size_t)k * nq + i];
      } else if (continuous[iv]) {
        Q[iq] = std::cos(s.q[(size_t)k * nq + ours]);
        Q[iq + 1] = std::sin(s.q[(size_t)k * nq + ours]);
      } else {
        for (int i = 0; i < joint.nv(); ++i) Q[iq + i] = s.q[(size_t)k * nq + ours + i];
      }
    }
    s.Q.push_back(Q);
    s.V.push_back(V);
    s.Vd.push_back(Vd);
    s.T.push_back(T);
  }
  return s;
}

// Pinocchio's batch timer: the same loop shape as the C ones (bench.h).
template <typename Call>
double batch(int count, int calls, int first, double *cpu_ns, Call &&call) {
  double acc = 0.0;
  int i = first;
  const double c0 = bench_cpu_now_ns(), t0 = bench_now_ns();
  for (int k = 0; k < calls; ++k) {
    acc += call(i);
    if (++i == count) i = 0;
  }
  const double t1 = bench_now_ns(), c1 = bench_cpu_now_ns();
  bench_sink += acc;
  *cpu_ns = (c1 - c0) / calls;
  return (t1 - t0) / calls;
}

// One pair timed in interleaved batches (the generated timer, then each Pinocchio variant, on the same states);
// writes the pair's JSON object (with `extra` fields appended) and a line on stderr.
// `peers`: (label, timer, relative error against Pinocchio) of other code for the same routine (the generated C at
// -O3, the CasADi peer), timed in the same batches right after the generated one.
struct Peer {
  std::string label;
  bench_timer timer;
  double err;
};

void time_pair(FILE *out, bool first_pair, const std::string &robot, const char *role, const char *pinocchio,
               const std::vector<std::pair<std::string, Timer>> &pin_timer, bench_timer ours,
               const bench_states &cs, double *buf, double seconds, int calls, double err,
               const std::string &extra = "", const std::vector<Peer> &peers = {}) {
  const int nv = (int)pin_timer.size(), nstates = cs.count, npeers = (int)peers.size();
  // warm-up and calibration: once through all states on each side
  double cpu = 0.0, tg = 0.0, tp = 0.0;
  for (int first = 0; first < nstates; first += calls) {
    tg += ours(&cs, first, calls, buf, &cpu) * calls;
    for (int e = 0; e < npeers; ++e) tg += peers[e].timer(&cs, first, calls, buf, &cpu) * calls;
    for (int v = 0; v < nv; ++v) tp += pin_timer[v].second(first, &cpu) * calls;
  }
  const double per_batch = (tg + tp) / nstates * calls;  // ns for one generated + one Pinocchio batch each
  int batches = (int)std::ceil(seconds * 1e9 / per_batch);
  batches = std::max(51, std::min(batches, 400001));
  std::vector<double> g(batches), gc(batches);
  std::vector<std::vector<double>> p(nv, std::vector<double>(batches)), pc(nv, std::vector<double>(batches));
  std::vector<std::vector<double>> e(npeers, std::vector<double>(batches)), ec(npeers, std::vector<double>(batches));
  for (int b = 0; b < batches; ++b) {
    const int first = (int)(((long long)b * calls) % nstates);
    g[b] = ours(&cs, first, calls, buf, &gc[b]);
    for (int k = 0; k < npeers; ++k) e[k][b] = peers[k].timer(&cs, first, calls, buf, &ec[k][b]);
    for (int v = 0; v < nv; ++v) p[v][b] = pin_timer[v].second(first, &pc[v][b]);
  }
  int best = 0;
  for (int v = 1; v < nv; ++v)
    if (median(p[v]) < median(p[best])) best = v;
  const double mg = median(g), mp = median(p[best]), mgc = median(gc), mpc = median(pc[best]);
  std::string label = pinocchio;
  if (nv > 1) label += " (" + pin_timer[best].first + ")";
  std::string variants = "{";
  for (int v = 0; v < nv; ++v)
    variants += std::string(v ? ", " : "") + "\"" + (nv > 1 ? pin_timer[v].first : "default") + "\": " +
                std::to_string(median(p[v]));
  variants += "}";
  std::string peers_json = "{";
  for (int k = 0; k < npeers; ++k) {
    char one[400];
    std::snprintf(one, sizeof one,
                  "%s\"%s\": {\"ns\": %.3f, \"ns_q10\": %.3f, \"ns_q90\": %.3f, \"cpu_ns\": %.3f, "
                  "\"relative_error\": %.3e}",
                  k ? ", " : "", peers[k].label.c_str(), median(e[k]), quantile(e[k], 0.1), quantile(e[k], 0.9),
                  median(ec[k]), peers[k].err);
    peers_json += one;
  }
  peers_json += "}";
  std::fprintf(out,
               "%s{\"role\": \"%s\", \"pinocchio\": \"%s\", \"batches\": %d, \"generated_ns\": %.3f, "
               "\"pinocchio_ns\": %.3f, \"ratio\": %.5f, \"generated_ns_q10\": %.3f, \"generated_ns_q90\": %.3f, "
               "\"pinocchio_ns_q10\": %.3f, \"pinocchio_ns_q90\": %.3f, \"generated_cpu_ns\": %.3f, "
               "\"pinocchio_cpu_ns\": %.3f, \"cpu_ratio\": %.5f, \"pinocchio_variants_ns\": %s, "
               "\"check_states\": %d, \"relative_error\": %.3e, \"peers\": %s%s}",
               first_pair ? "" : ", ", role, label.c_str(), batches, mg, mp, mg / mp, quantile(g, 0.1),
               quantile(g, 0.9), quantile(p[best], 0.1), quantile(p[best], 0.9), mgc, mpc, mgc / mpc,
               variants.c_str(), std::min(CHECK_STATES, nstates), err, peers_json.c_str(), extra.c_str());
  std::fprintf(stderr,
               "%s %-18s generated %9.1f ns  Pinocchio %-24s %9.1f ns  ratio %.3f  (CPU-time ratio %.3f, "
               "err %.1e, %d batches of %d)\n",
               robot.c_str(), role, mg, label.c_str(), mp, mg / mp, mgc / mpc, err, batches, calls);
  for (int k = 0; k < npeers; ++k)
    std::fprintf(stderr, "%s %-18s   %-14s %9.1f ns  generated/it %.3f  (err %.1e)\n", robot.c_str(), role,
                 peers[k].label.c_str(), median(e[k]), mg / median(e[k]), peers[k].err);
}

}  // namespace

#endif
