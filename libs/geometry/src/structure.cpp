// Contact structure: coordination with and without rattlers, per phase pair.
#include <algorithm>

#include "tomodem/geometry/pack.hpp"

namespace tomodem::geometry {

ContactStructure contact_structure(std::size_t n, const std::vector<int32_t>& phase, int n_phases,
                                   const ContactTable& contacts, int min_contacts) {
  ContactStructure cs;
  cs.z_ij.assign(std::size_t(n_phases), std::vector<double>(std::size_t(n_phases), 0.0));
  cs.rattler.assign(n, 0);
  if (n == 0) return cs;
  // Force-bearing contacts: a positive normal force component along the branch is not needed,
  // a non-zero normal force is (adhesive contacts in tension bear force too).
  std::vector<std::pair<int32_t, int32_t>> c;
  for (std::size_t k = 0; k < contacts.size(); ++k)
    if (norm(contacts.normal_force[k]) > 0 && contacts.i[k] != contacts.j[k]) c.emplace_back(contacts.i[k], contacts.j[k]);
  std::vector<int> z(n, 0);
  for (const auto& [i, j] : c) ++z[std::size_t(i)], ++z[std::size_t(j)];
  cs.coordination = 2.0 * double(c.size()) / double(n);
  std::vector<long> count(std::size_t(n_phases), 0);
  for (std::size_t i = 0; i < n; ++i) ++count[std::size_t(phase[i])];
  for (const auto& [i, j] : c) {
    cs.z_ij[std::size_t(phase[std::size_t(i)])][std::size_t(phase[std::size_t(j)])] += 1;
    cs.z_ij[std::size_t(phase[std::size_t(j)])][std::size_t(phase[std::size_t(i)])] += 1;
  }
  for (int a = 0; a < n_phases; ++a)
    for (int b = 0; b < n_phases; ++b)
      if (count[std::size_t(a)] > 0) cs.z_ij[std::size_t(a)][std::size_t(b)] /= double(count[std::size_t(a)]);
  // Rattlers, recursively: removing one lowers its neighbours' counts.
  std::vector<std::vector<int32_t>> adj(n);
  for (const auto& [i, j] : c) adj[std::size_t(i)].push_back(j), adj[std::size_t(j)].push_back(i);
  std::vector<int32_t> stack;
  for (std::size_t i = 0; i < n; ++i)
    if (z[i] < min_contacts) cs.rattler[i] = 1, stack.push_back(int32_t(i));
  while (!stack.empty()) {
    const int32_t i = stack.back();
    stack.pop_back();
    for (int32_t j : adj[std::size_t(i)])
      if (!cs.rattler[std::size_t(j)] && --z[std::size_t(j)] < min_contacts) cs.rattler[std::size_t(j)] = 1, stack.push_back(j);
  }
  long nr = 0, zsum = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (cs.rattler[i]) ++nr;
    else zsum += z[i];
  cs.rattler_fraction = double(nr) / double(n);
  cs.coordination_no_rattlers = nr < long(n) ? double(zsum) / double(long(n) - nr) : 0.0;
  return cs;
}

}  // namespace tomodem::geometry
