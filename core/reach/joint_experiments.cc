#include "core/reach/joint_experiments.h"

#include <utility>

namespace canalid::core {
namespace {

// The experiment an operator's `name` means on this reach (empty: its only one, else none).
std::string_view Resolved(const ReachController& reach, std::string_view name) {
  if (!name.empty()) return name;
  const auto& all = reach.options().experiments;
  return all.size() == 1 ? std::string_view(all.front().name) : std::string_view();
}

ReachController* At(std::span<ReachController* const> reaches, std::size_t index) {
  return index < reaches.size() ? reaches[index] : nullptr;
}

// Why a partner's experiment would not start now (empty: it would).
std::string PartnerRefusal(const JointExperiment::Member& partner, const ReachController& other) {
  std::string refusal = other.StartRefusal(partner.experiment);
  if (refusal.empty()) return refusal;
  std::string why = "experiment '";
  why += partner.experiment;
  why += "' on reach ";
  why += other.name();
  why += " cannot start: ";
  why += refusal;
  return why;
}

}  // namespace

JointExperiments::JointExperiments(std::vector<JointExperiment> joints)
    : joints_(std::move(joints)), active_(joints_.size(), 0) {}

std::string JointExperiments::StartRefusal(std::span<ReachController* const> reaches,
                                           std::size_t reach, std::string_view name) const {
  const ReachController* leader = At(reaches, reach);
  if (leader == nullptr) return "no such reach";
  if (std::string own = leader->StartRefusal(name); !own.empty()) return own;
  const std::string_view experiment = Resolved(*leader, name);
  for (const JointExperiment& joint : joints_) {
    if (joint.leader.reach != reach || joint.leader.experiment != experiment) continue;
    for (const JointExperiment::Member& partner : joint.partners) {
      const ReachController* other = At(reaches, partner.reach);
      if (other == nullptr) continue;
      if (std::string refusal = PartnerRefusal(partner, *other); !refusal.empty()) {
        return "its joint " + refusal;
      }
    }
  }
  return {};
}

bool JointExperiments::HasOtherMember(std::size_t reach, std::string_view experiment) const {
  for (const JointExperiment& joint : joints_) {
    if (joint.partners.empty()) continue;  // every partner is on another reach than the leader
    if (joint.leader.reach == reach && joint.leader.experiment == experiment) return true;
    for (const JointExperiment::Member& partner : joint.partners) {
      if (partner.reach == reach && partner.experiment == experiment) return true;
    }
  }
  return false;
}

bool JointExperiments::OnStartAllowed(std::span<ReachController* const> reaches,
                                      std::size_t reach) const {
  const ReachController* leader = At(reaches, reach);
  if (leader == nullptr) return true;
  for (const ReachExperiment& experiment : leader->options().experiments) {
    if (!experiment.start_on_start) continue;
    for (const JointExperiment& joint : joints_) {
      if (joint.leader.reach != reach || joint.leader.experiment != experiment.name) continue;
      for (const JointExperiment::Member& partner : joint.partners) {
        const ReachController* other = At(reaches, partner.reach);
        if (other != nullptr && !other->StartRefusal(partner.experiment).empty()) return false;
      }
    }
  }
  return true;
}

void JointExperiments::EndOthers(std::span<ReachController* const> reaches, std::size_t j,
                                 std::size_t except, Ending how, const std::string& why,
                                 std::vector<JointOrder>* orders) const {
  const JointExperiment& joint = joints_[j];
  auto end = [&](const JointExperiment::Member& member) {
    ReachController* controller = At(reaches, member.reach);
    if (member.reach == except || controller == nullptr) return;
    if (!IsRunning(controller->pipeline().experiment_state().phase) ||
        controller->experiment_name() != member.experiment) {
      return;
    }
    orders->push_back({member.reach,
                       how == Ending::kDone ? controller->EndJoint() : controller->StopJoint(),
                       why});
  };
  end(joint.leader);
  for (const JointExperiment::Member& partner : joint.partners) end(partner);
}

std::vector<JointOrder> JointExperiments::AfterPhaseChange(
    std::span<ReachController* const> reaches, std::size_t reach) {
  std::vector<JointOrder> orders;
  ReachController* changed = At(reaches, reach);
  if (changed == nullptr) return orders;
  const ExperimentPhase phase = changed->pipeline().experiment_state().phase;
  const std::string& name = changed->experiment_name();
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    const JointExperiment& joint = joints_[j];
    if (joint.leader.reach == reach && joint.leader.experiment == name) {
      if (IsRunning(phase) && active_[j] == 0) {
        std::string refusal;
        for (const JointExperiment::Member& partner : joint.partners) {
          const ReachController* other = At(reaches, partner.reach);
          if (other == nullptr || !refusal.empty()) continue;
          refusal = PartnerRefusal(partner, *other);
        }
        if (!refusal.empty()) {
          orders.push_back({reach, changed->StopJoint(), refusal});
          continue;
        }
        active_[j] = 1;
        for (const JointExperiment::Member& partner : joint.partners) {
          ReachController* other = At(reaches, partner.reach);
          if (other == nullptr) continue;
          orders.push_back({partner.reach, other->Start(partner.experiment),
                            "started with experiment '" + name + "' of reach " + changed->name()});
        }
      } else if (!IsRunning(phase) && active_[j] != 0) {
        // Its excitation is over (identifying): the partners end with it; it aborted: they stop.
        active_[j] = 0;
        EndOthers(reaches, j, reach,
                  phase == ExperimentPhase::kAborted ? Ending::kAborted : Ending::kDone,
                  "experiment '" + name + "' of reach " + changed->name() + " is " +
                      ExperimentPhaseName(phase),
                  &orders);
      }
      continue;
    }
    if (active_[j] == 0 || phase != ExperimentPhase::kAborted) continue;
    for (const JointExperiment::Member& partner : joint.partners) {
      if (partner.reach != reach || partner.experiment != name) continue;
      active_[j] = 0;
      EndOthers(reaches, j, reach, Ending::kAborted,
                "experiment '" + name + "' of reach " + changed->name() + " aborted (" +
                    AbortReasonName(changed->pipeline().experiment_state().abort_reason) + ")",
                &orders);
      break;
    }
  }
  return orders;
}

}  // namespace canalid::core
