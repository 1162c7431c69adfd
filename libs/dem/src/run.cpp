// Running a scene's protocol: measurements, stop criteria, progress, checkpoints.
#include <chrono>
#include <cmath>
#include <cstdio>

#include "tomodem/core/progress.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/scene.hpp"

namespace tomodem::dem {

const std::vector<std::string>& series_columns() {
  static const std::vector<std::string> c = {
      "step", "time_s", "kinetic_energy_J", "elastic_energy_J", "dissipated_energy_J", "external_work_J", "pressure_Pa",
      "stress_xx_Pa", "stress_yy_Pa", "stress_zz_Pa", "stress_xy_Pa", "stress_xz_Pa", "stress_yz_Pa", "coordination",
      "unbalanced_force_ratio", "inertial_number", "volume_m3"};
  return c;
}

std::vector<double> series_row(const Measurements& m) {
  return {double(m.step), m.time, m.kinetic_energy, m.elastic_energy, m.dissipated_energy, m.external_work,
          m.pressure, m.stress(0, 0), m.stress(1, 1), m.stress(2, 2), m.stress(0, 1), m.stress(0, 2),
          m.stress(1, 2), m.coordination, m.unbalanced_force_ratio, m.inertial_number, m.volume};
}

std::vector<std::vector<double>> full_series(const Scene& scene, const std::vector<Measurements>& run) {
  std::vector<std::vector<double>> rows = scene.series_before;
  for (const auto& m : run) {
    if (!rows.empty() && rows.back()[0] >= double(m.step)) continue;  // the restart step, already there
    rows.push_back(series_row(m));
  }
  return rows;
}

RunReport run_protocol(Scene& scene, const std::string& checkpoint_path, bool progress) {
  Simulation& sim = *scene.sim;
  const Protocol& p = scene.protocol;
  RunReport rep;
  rep.stop_reason = "steps";
  const long first = sim.step_count();
  rep.series.push_back(sim.measure());
  const StepObserver& observer = scene.observer;
  const long every = observer.at_step ? observer.every : 0;
  if (every > 0 && first % every == 0) observer.at_step(sim);
  const auto t0 = std::chrono::steady_clock::now();
  Progress bar("steps", double(p.steps - first));
  while (sim.step_count() < p.steps) {
    // Advance to the next output row (or checkpoint), whichever comes first.
    long next = std::min(p.steps, (sim.step_count() / p.output_interval + 1) * p.output_interval);
    if (p.checkpoint_interval > 0)
      next = std::min(next, (sim.step_count() / p.checkpoint_interval + 1) * p.checkpoint_interval);
    if (every > 0) next = std::min(next, (sim.step_count() / every + 1) * every);
    sim.run(next - sim.step_count());
    if (every > 0 && sim.step_count() % every == 0) observer.at_step(sim);
    if (sim.step_count() % p.output_interval == 0 || sim.step_count() == p.steps) {
      const Measurements m = sim.measure();
      rep.series.push_back(m);
      if (p.stop_unbalanced_force > 0 && m.contacts > 0 && m.unbalanced_force_ratio < p.stop_unbalanced_force) {
        rep.stop_reason = "unbalanced_force";
        break;
      }
      if (p.stop_kinetic_energy > 0 && m.kinetic_energy < p.stop_kinetic_energy) {
        rep.stop_reason = "kinetic_energy";
        break;
      }
    }
    if (p.checkpoint_interval > 0 && !checkpoint_path.empty() && sim.step_count() % p.checkpoint_interval == 0)
      write_checkpoint(checkpoint_path, sim, scene.text, full_series(scene, rep.series));
    if (progress) {
      const Measurements& m = rep.series.back();
      char d[160];
      std::snprintf(d, sizeof d, "step %ld/%ld, t = %.4g s, KE %.3g J, p %.4g Pa, Z %.3f", sim.step_count(), p.steps,
                    sim.time(), m.kinetic_energy, m.pressure, m.coordination);
      bar.update(double(sim.step_count() - first), d);
    }
  }
  if (progress) bar.finish(rep.stop_reason);
  rep.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  rep.steps = sim.step_count() - first;
  rep.particle_steps_per_second = rep.wall_time_s > 0 ? double(rep.steps) * sim.particles().size() / rep.wall_time_s : 0;
  if (rep.series.back().step != sim.step_count()) rep.series.push_back(sim.measure());
  rep.final = rep.series.back();
  return rep;
}

}  // namespace tomodem::dem
