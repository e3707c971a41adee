// The derivatives of constrained dynamics and of impacts: aggsym's generated C against Pinocchio C++ (the `pin`
// wheel), same states, same process (benchmarks/runtime/constrained_derivatives.py builds and runs it).
//
//   constrained_derivatives_bench SECONDS STATES CALLS OUT.json NAME URDF ROOT CONTACTS [NAME URDF ROOT CONTACTS ...]
//
// ROOT: "free" (the model was generated with --floating-base quaternion: Pinocchio's JointModelFreeFlyer) or
// "fixed"; CONTACTS: FRAME:3 (a point contact of the frame's origin with the world) or FRAME:6 (a weld),
// comma-separated, in the order of the generated code's constraints.  Pinocchio's side: one RigidConstraintModel
// per contact (CONTACT_3D, CONTACT_6D; joint2 the world), initConstraintDynamics once, default ProximalSettings
// (mu = 0, one iteration: an exact solve), the contacts in LOCAL_WORLD_ALIGNED (aggsym's rows) and in LOCAL, the
// faster of the two counting.
//
// States: q uniform in [-pi, pi] (a free-flyer's quaternion a random unit one), tau standard normal, a velocity v
// standard normal; states where the Delassus matrix G = J M^-1 J^T has a condition number above 1e6 are drawn
// again (two exact double-precision solves differ by about cond(G) 1e-16).  The constrained forward dynamics is
// evaluated at v projected onto the null space of J (a weld's drift in Pinocchio is the spatial acceleration,
// aggsym's the classical one: they agree where J v = 0), the impact at v itself with restitution r (the record's).
//
// Agreement first, on the first CHECK_STATES states: d qdd / d(q, v, tau) against data.ddq_dq, ddq_dv, ddq_dtau
// (both reference frames), d (J^T lambda) / d(q, v, tau) against computeRNEADerivatives at (q, v, qdd) + M d qdd
// (and M ddq_dtau - I); d qd+ / dq against ddq_dq, d qd+ / d qd- against ddq_dv + I (Pinocchio's ddq_dv is the
// change of qd+ - qd-), d (J^T Lambda) / dq against computeRNEADerivatives at v = 0, a = qd+ - qd- without gravity
// plus M ddq_dq, d (J^T Lambda) / d qd- against M ddq_dv.  Each matrix on its own scale (largest entry); a model
// with an error above TOLERANCE stops the program before anything is timed.  (Pinocchio 4.1's
// computeImpulseDynamicsDerivatives needs data.dvc_dq cleared before each call on a Data used before: done here,
// inside its timed part.)
//
// Then four pairs, each timed in interleaved batches (pinocchio_common.hpp's time_pair):
//   constrained_forward_dynamics_derivatives alone  vs  computeConstraintDynamicsDerivatives alone: each call
//     after an untimed constraintDynamics at the same state (Pinocchio requires it), the derivatives' call alone
//     timed (two clock reads around it, tens of ns against tens of microseconds);
//   constrained_forward_dynamics + its derivatives  vs  constraintDynamics + computeConstraintDynamicsDerivatives;
//   impulse_dynamics_derivatives alone  vs  computeImpulseDynamicsDerivatives alone (after an untimed
//     impulseDynamics);
//   impulse_dynamics + its derivatives  vs  impulseDynamics + computeImpulseDynamicsDerivatives.
#define PINOCCHIO_DISABLE_UNSUPPORTED_WARNINGS  // the constrained and impulse dynamics: "the API will change"
#include <pinocchio/algorithm/constrained-dynamics-derivatives.hpp>
#include <pinocchio/algorithm/constrained-dynamics.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/impulse-dynamics-derivatives.hpp>
#include <pinocchio/algorithm/impulse-dynamics.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/rnea-derivatives.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/parsers/urdf.hpp>

#include <Eigen/Eigenvalues>

#include <cstdlib>
#include <cstring>

#include "bench.h"
#include "contact_bench.h"
#include "pinocchio_common.hpp"

namespace {

const double MAX_CONDITION = 1e6;
const double TOLERANCE = 1e-8;  // largest relative error of a derivative block before anything is timed
const pinocchio::ReferenceFrame CONTACT_FRAME[] = {pinocchio::LOCAL_WORLD_ALIGNED, pinocchio::LOCAL};
const char *const CONTACT_FRAME_NAME[] = {"LOCAL_WORLD_ALIGNED", "LOCAL"};

struct Contact {
  std::string frame;
  int size;  // 3: a point, 6: a weld
};

std::vector<Contact> parse_contacts(const std::string &text) {
  std::vector<Contact> out;
  for (size_t at = 0; at < text.size();) {
    const size_t end = std::min(text.find(',', at), text.size());
    const std::string item = text.substr(at, end - at);
    const size_t colon = item.rfind(':');
    out.push_back({item.substr(0, colon), colon == std::string::npos ? 0 : std::atoi(item.c_str() + colon + 1)});
    at = end + 1;
  }
  return out;
}

Eigen::MatrixXd symmetric(const Eigen::MatrixXd &upper) {
  Eigen::MatrixXd M = upper.triangularView<Eigen::Upper>();
  M.triangularView<Eigen::StrictlyLower>() = M.transpose().triangularView<Eigen::StrictlyLower>();
  return M;
}

// State k of `from` appended to `to`.
void take_state(const States &from, int k, States &to) {
  const size_t nq = (size_t)from.nq, nv = (size_t)from.nv;
  to.q.insert(to.q.end(), from.q.begin() + k * nq, from.q.begin() + (k + 1) * nq);
  to.qd.insert(to.qd.end(), from.qd.begin() + k * nv, from.qd.begin() + (k + 1) * nv);
  to.qdd.insert(to.qdd.end(), from.qdd.begin() + k * nv, from.qdd.begin() + (k + 1) * nv);
  to.tau.insert(to.tau.end(), from.tau.begin() + k * nv, from.tau.begin() + (k + 1) * nv);
  to.Q.push_back(from.Q[k]);
  to.V.push_back(from.V[k]);
  to.Vd.push_back(from.Vd[k]);
  to.T.push_back(from.T[k]);
  ++to.count;
}

// A Pinocchio timer that times `timed(i)` alone, after `untimed(i)` (the call it requires) at the same state:
// the same loop as batch(), with the clocks read around each timed call.
template <typename Untimed, typename Timed>
double batch_after(int count, int calls, int first, double *cpu_ns, Untimed &&untimed, Timed &&timed) {
  double acc = 0.0, wall = 0.0, cpu = 0.0;
  int i = first;
  for (int k = 0; k < calls; ++k) {
    untimed(i);
    const double c0 = bench_cpu_now_ns(), t0 = bench_now_ns();
    acc += timed(i);
    const double t1 = bench_now_ns(), c1 = bench_cpu_now_ns();
    wall += t1 - t0;
    cpu += c1 - c0;
    if (++i == count) i = 0;
  }
  bench_sink += acc;
  *cpu_ns = cpu / calls;
  return wall / calls;
}

int bench_contacts(FILE *out, bool first_model, const std::string &name, const std::string &path,
                   const std::string &root, const std::string &contact_list, unsigned seed, double seconds,
                   int nstates, int calls) {
  const bench_contact_model *bm = nullptr;
  for (int k = 0; bench_contact_models[k]; ++k)
    if (name == bench_contact_models[k]->name) bm = bench_contact_models[k];
  if (!bm) {
    std::fprintf(stderr, "no generated contact model %s linked in\n", name.c_str());
    return 2;
  }
  pinocchio::Model model;
  if (root == "free")
    pinocchio::urdf::buildModel(path, pinocchio::JointModelFreeFlyer(), model);
  else
    pinocchio::urdf::buildModel(path, model);
  const int n = bm->nv, nc = bm->nc;
  if (model.nv != n || (root == "free") != (bm->free_flyer == 1)) {
    std::fprintf(stderr, "%s: Pinocchio nv = %d, generated nv = %d (root %s)\n", name.c_str(), (int)model.nv, n,
                 root.c_str());
    return 1;
  }
  std::vector<int> continuous;
  if (!same_joints(model, bm->joints, name, continuous)) return 1;
  const std::vector<Contact> contacts = parse_contacts(contact_list);
  int rows = 0;
  for (const Contact &c : contacts) {
    if ((c.size != 3 && c.size != 6) || !model.existFrame(c.frame)) {
      std::fprintf(stderr, "%s: contact %s:%d (a frame of the model, 3 or 6 rows)\n", name.c_str(), c.frame.c_str(),
                   c.size);
      return 1;
    }
    rows += c.size;
  }
  if (rows != nc) {
    std::fprintf(stderr, "%s: %d contact rows, %d in the generated code\n", name.c_str(), rows, nc);
    return 1;
  }
  ConstraintModels cmodels[2];
  for (const Contact &c : contacts) {
    const pinocchio::Frame &f = model.frames[model.getFrameId(c.frame)];
    for (int v = 0; v < 2; ++v)
      cmodels[v].emplace_back(c.size == 3 ? pinocchio::CONTACT_3D : pinocchio::CONTACT_6D, model, f.parentJoint,
                              f.placement, CONTACT_FRAME[v]);
  }
  // one Data (and constraint datas) per frame convention and routine
  ConstraintDatas cdatas[2][2];
  std::vector<pinocchio::Data> data(4, pinocchio::Data(model));
  for (int v = 0; v < 2; ++v)
    for (int w = 0; w < 2; ++w) {
      for (const auto &c : cmodels[v]) cdatas[w][v].emplace_back(c);
      pinocchio::initConstraintDynamics(model, data[2 * w + v], cmodels[v], cdatas[w][v]);
    }
  pinocchio::ProximalSettings settings;  // mu = 0, one iteration: an exact solve (Pinocchio writes its counts in it)

  // states with cond(G) <= MAX_CONDITION; qd projected onto the null space of J, qdd the velocity before impact
  pinocchio::Data kin(model);
  Eigen::MatrixXd J(nc, n), J6(6, n);
  auto jacobian = [&](const Eigen::VectorXd &Q) {
    pinocchio::computeJointJacobians(model, kin, Q);
    int row = 0;
    for (const auto &c : cmodels[0]) {
      J6.setZero();
      pinocchio::getFrameJacobian(model, kin, c.joint1_id, c.joint1_placement, pinocchio::LOCAL_WORLD_ALIGNED, J6);
      const int size = c.type == pinocchio::CONTACT_3D ? 3 : 6;
      J.middleRows(row, size) = J6.topRows(size);
      row += size;
    }
    return symmetric(pinocchio::crba(model, kin, Q));
  };
  const bool free_flyer = bm->free_flyer == 1;
  States drawn = random_states(model, continuous, 8 * nstates, seed, free_flyer), s;
  s.nq = drawn.nq;
  s.nv = drawn.nv;
  int rejected = 0;
  for (int k = 0; k < drawn.count && s.count < nstates; ++k) {
    const Eigen::MatrixXd M = jacobian(drawn.Q[k]);
    const Eigen::MatrixXd G = J * M.ldlt().solve(J.transpose());
    const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(G).eigenvalues();
    if (!(ev.minCoeff() > 0 && ev.maxCoeff() <= MAX_CONDITION * ev.minCoeff())) {
      ++rejected;
      continue;
    }
    const int at = s.count;
    take_state(drawn, k, s);
    const Eigen::VectorXd before = s.V[at];
    s.V[at] -= J.transpose() * (J * J.transpose()).ldlt().solve(J * s.V[at]);
    s.Vd[at] = before;
    for (int i = 0; i < n; ++i) {
      s.qd[(size_t)at * n + i] = s.V[at][i];
      s.qdd[(size_t)at * n + i] = before[i];
    }
  }
  if (s.count < nstates) {
    std::fprintf(stderr, "%s: %d of %d states with cond(G) <= %g\n", name.c_str(), s.count, nstates, MAX_CONDITION);
    if (s.count < 1) return 1;
  }
  bench_states cs = {s.count, s.nq, n, s.q.data(), s.qd.data(), s.qdd.data(), s.tau.data(), bm->p};
  const size_t nn = (size_t)n * n;
  std::vector<double> buf(6 * nn + 2 * (size_t)n + (size_t)nc);
  const double r = bm->r;

  // agreement on the first states
  pinocchio::Model still = model;
  still.gravity.setZero();
  pinocchio::Data still_data(still), rnea_data(model);
  double err_cfd[6] = {0, 0, 0, 0, 0, 0}, err_imp[4] = {0, 0, 0, 0};
  int singular = 0;
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  for (int k = 0; k < std::min(CHECK_STATES, s.count); ++k) {
    const double *q = &s.q[(size_t)k * s.nq], *qd = &s.qd[(size_t)k * n], *qm = &s.qdd[(size_t)k * n];
    const Eigen::MatrixXd M = jacobian(s.Q[k]);
    singular += bm->constrained_forward_dynamics_derivatives(q, qd, &s.tau[(size_t)k * n], bm->p, buf.data(),
                                                             buf.data() + nn, buf.data() + 2 * nn,
                                                             buf.data() + 3 * nn, buf.data() + 4 * nn,
                                                             buf.data() + 5 * nn) != 0;
    for (int v = 0; v < 2; ++v) {
      pinocchio::Data &d = data[v];
      pinocchio::constraintDynamics(model, d, s.Q[k], s.V[k], s.T[k], cmodels[v], cdatas[0][v], settings);
      pinocchio::computeConstraintDynamicsDerivatives(model, d, cmodels[v], cdatas[0][v], settings);
      const Eigen::MatrixXd want[3] = {d.ddq_dq, d.ddq_dv, d.ddq_dtau};
      for (int b = 0; b < 3; ++b)
        err_cfd[b] = std::max(err_cfd[b], relative_error(buf.data() + b * nn, row_major(want[b]).data(), n * n));
      if (v) continue;
      pinocchio::computeRNEADerivatives(model, rnea_data, s.Q[k], s.V[k], d.ddq);
      const Eigen::MatrixXd jt[3] = {rnea_data.dtau_dq + M * d.ddq_dq, rnea_data.dtau_dv + M * d.ddq_dv,
                                     M * d.ddq_dtau - I};
      for (int b = 0; b < 3; ++b)
        err_cfd[3 + b] = std::max(err_cfd[3 + b],
                                  relative_error(buf.data() + (3 + b) * nn, row_major(jt[b]).data(), n * n));
    }
    singular += bm->impulse_dynamics_derivatives(q, qm, &r, bm->p, buf.data(), buf.data() + nn, buf.data() + 2 * nn,
                                                 buf.data() + 3 * nn) != 0;
    for (int v = 0; v < 2; ++v) {
      pinocchio::Data &d = data[2 + v];
      const Eigen::VectorXd plus =
          pinocchio::impulseDynamics(model, d, s.Q[k], s.Vd[k], cmodels[v], cdatas[1][v], r, settings);
      d.dvc_dq.setZero();  // see imp_derivatives
      pinocchio::computeImpulseDynamicsDerivatives(model, d, cmodels[v], cdatas[1][v], r, settings);
      const Eigen::MatrixXd want[2] = {d.ddq_dq, d.ddq_dv + I};
      for (int b = 0; b < 2; ++b)
        err_imp[b] = std::max(err_imp[b], relative_error(buf.data() + b * nn, row_major(want[b]).data(), n * n));
      if (v) continue;
      pinocchio::computeRNEADerivatives(still, still_data, s.Q[k], Eigen::VectorXd::Zero(n), plus - s.Vd[k]);
      const Eigen::MatrixXd jt[2] = {still_data.dtau_dq + M * d.ddq_dq, M * d.ddq_dv};
      for (int b = 0; b < 2; ++b)
        err_imp[2 + b] = std::max(err_imp[2 + b],
                                  relative_error(buf.data() + (2 + b) * nn, row_major(jt[b]).data(), n * n));
    }
  }
  const double worst_cfd = *std::max_element(err_cfd, err_cfd + 6);
  const double worst_imp = *std::max_element(err_imp, err_imp + 4);
  if (!(worst_cfd <= TOLERANCE && worst_imp <= TOLERANCE)) {  // no time for code that computes something else
    std::fprintf(stderr,
                 "%s: the derivatives disagree with Pinocchio's (relative errors: d qdd %.1e %.1e %.1e, d J^T lambda "
                 "%.1e %.1e %.1e, d qd+ %.1e %.1e, d J^T Lambda %.1e %.1e; tolerance %g)\n",
                 name.c_str(), err_cfd[0], err_cfd[1], err_cfd[2], err_cfd[3], err_cfd[4], err_cfd[5], err_imp[0],
                 err_imp[1], err_imp[2], err_imp[3], TOLERANCE);
    return 1;
  }

  // Pinocchio's timers, per convention v: the derivatives alone (after an untimed value), and the pair
  auto cfd_value = [&](int v) {
    return [&, v](int i) {
      pinocchio::constraintDynamics(model, data[v], s.Q[i], s.V[i], s.T[i], cmodels[v], cdatas[0][v], settings);
      return data[v].ddq[0];
    };
  };
  auto cfd_derivatives = [&](int v) {
    return [&, v](int) {
      pinocchio::computeConstraintDynamicsDerivatives(model, data[v], cmodels[v], cdatas[0][v], settings);
      return data[v].ddq_dq(0, 0);
    };
  };
  auto imp_value = [&](int v) {
    return [&, v](int i) {
      pinocchio::impulseDynamics(model, data[2 + v], s.Q[i], s.Vd[i], cmodels[v], cdatas[1][v], r, settings);
      return data[2 + v].dq_after[0];
    };
  };
  // Pinocchio 4.1's computeImpulseDynamicsDerivatives subtracts from data.dvc_dq without clearing it first (its
  // own "TODO: User should make sure the internal quantities are reset"): on a Data used before, its derivatives
  // along q are wrong (measured: 0.05 to 1 relative).  The clearing a correct call needs is part of its time.
  auto imp_derivatives = [&](int v) {
    return [&, v](int) {
      data[2 + v].dvc_dq.setZero();
      pinocchio::computeImpulseDynamicsDerivatives(model, data[2 + v], cmodels[v], cdatas[1][v], r, settings);
      return data[2 + v].ddq_dq(0, 0);
    };
  };
  auto alone = [&](auto make_value, auto make_derivatives) {
    std::vector<std::pair<std::string, Timer>> out;
    for (int v = 0; v < 2; ++v)
      out.push_back({CONTACT_FRAME_NAME[v], [&, v, make_value, make_derivatives](int first, double *cpu) {
                       return batch_after(s.count, calls, first, cpu, make_value(v), make_derivatives(v));
                     }});
    return out;
  };
  auto paired = [&](auto make_value, auto make_derivatives) {
    std::vector<std::pair<std::string, Timer>> out;
    for (int v = 0; v < 2; ++v)
      out.push_back({CONTACT_FRAME_NAME[v], [&, v, make_value, make_derivatives](int first, double *cpu) {
                       auto value = make_value(v);
                       auto derivatives = make_derivatives(v);
                       return batch(s.count, calls, first, cpu, [&](int i) { return value(i) + derivatives(i); });
                     }});
    return out;
  };

  std::string contacts_json;
  for (const Contact &c : contacts)
    contacts_json += std::string(contacts_json.empty() ? "" : ", ") + "{\"frame\": \"" + json_escape(c.frame) +
                     "\", \"rows\": " + std::to_string(c.size) + "}";
  char errors[600];
  std::snprintf(errors, sizeof errors,
                "{\"dqdd_dq\": %.3e, \"dqdd_dqd\": %.3e, \"dqdd_dtau\": %.3e, \"dJtlambda_dq\": %.3e, "
                "\"dJtlambda_dqd\": %.3e, \"dJtlambda_dtau\": %.3e, \"dqd_plus_dq\": %.3e, "
                "\"dqd_plus_dqd_minus\": %.3e, \"dimpulse_dq\": %.3e, \"dimpulse_dqd_minus\": %.3e}",
                err_cfd[0], err_cfd[1], err_cfd[2], err_cfd[3], err_cfd[4], err_cfd[5], err_imp[0], err_imp[1],
                err_imp[2], err_imp[3]);
  std::fprintf(out,
               "%s{\"name\": \"%s\", \"urdf\": \"%s\", \"root\": \"%s\", \"nq\": %d, \"nv\": %d, \"nc\": %d, "
               "\"contacts\": [%s], \"r\": %g, \"states\": %d, \"rejected_states\": %d, \"max_condition\": %g, "
               "\"check_states\": %d, \"singular_check_states\": %d, \"relative_errors\": %s, \"pairs\": [",
               first_model ? "" : ", ", json_escape(name).c_str(), json_escape(path).c_str(), root.c_str(), s.nq, n,
               nc, contacts_json.c_str(), r, s.count, rejected, MAX_CONDITION, std::min(CHECK_STATES, s.count),
               singular, errors);
  time_pair(out, true, name, "constrained_forward_dynamics_derivatives",
            "computeConstraintDynamicsDerivatives (after an untimed constraintDynamics)",
            alone(cfd_value, cfd_derivatives), bm->t_cfd_derivatives, cs, buf.data(), seconds, calls, worst_cfd);
  time_pair(out, false, name, "constrained_forward_dynamics+derivatives",
            "constraintDynamics + computeConstraintDynamicsDerivatives", paired(cfd_value, cfd_derivatives),
            bm->t_cfd_with_value, cs, buf.data(), seconds, calls, worst_cfd);
  time_pair(out, false, name, "impulse_dynamics_derivatives",
            "computeImpulseDynamicsDerivatives (after an untimed impulseDynamics)", alone(imp_value, imp_derivatives),
            bm->t_impulse_derivatives, cs, buf.data(), seconds, calls, worst_imp);
  time_pair(out, false, name, "impulse_dynamics+derivatives", "impulseDynamics + computeImpulseDynamicsDerivatives",
            paired(imp_value, imp_derivatives), bm->t_impulse_with_value, cs, buf.data(), seconds, calls, worst_imp);
  std::fprintf(out, "]}");
  return 0;
}

}  // namespace

int main(int argc, char **argv) {
  if (argc < 9 || (argc - 5) % 4 != 0) {
    std::fprintf(stderr, "usage: %s SECONDS STATES CALLS OUT.json NAME URDF free|fixed FRAME:3|6,... [...]\n", argv[0]);
    return 2;
  }
  const double seconds = std::atof(argv[1]);
  const int nstates = std::atoi(argv[2]), calls = std::atoi(argv[3]);
  FILE *out = std::fopen(argv[4], "w");
  if (!out || nstates < 1 || calls < 1) {
    std::fprintf(stderr, "cannot write %s, or STATES/CALLS < 1\n", argv[4]);
    return 2;
  }
  std::fprintf(out, "{\"seconds_per_pair\": %g, \"states\": %d, \"calls_per_batch\": %d, \"models\": [", seconds,
               nstates, calls);
  for (int a = 5, k = 0; a < argc; a += 4, ++k) {
    const int rc = bench_contacts(out, k == 0, argv[a], argv[a + 1], argv[a + 2], argv[a + 3],
                                  20261128u + 3u * (unsigned)k, seconds, nstates, calls);
    if (rc) return rc;
    std::fflush(out);
  }
  std::fprintf(out, "], \"sink\": %g}\n", (double)bench_sink);
  std::fclose(out);
  return 0;
}
