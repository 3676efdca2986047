#include "daemon/canalidd/model_persistence.h"

#include <algorithm>
#include <string>

#include "daemon/canalidd/clock.h"
#include "daemon/canalidd/log.h"
#include "daemon/canalidd/persisted_model_checks.h"
#include "drivers/json/model_json.h"

namespace canalid::daemon {

void ResumePersistedModels(const StateStore& store,
                           const std::vector<std::unique_ptr<ReachRuntime>>& reaches,
                           LcmPublisher& publisher) {
  const StateLoadReport report = store.LoadAll();
  for (const std::string& problem : report.problems) LogWarning("state: " + problem);
  for (const auto& temp : report.leftover_temp_files) {
    LogWarning("state: " + temp.string() + ": left by an interrupted write; ignored");
  }
  for (const PersistedModel& model : report.models) {
    const auto reach = std::find_if(reaches.begin(), reaches.end(),
                                    [&](const auto& r) { return r->name() == model.reach; });
    if (reach == reaches.end()) continue;
    // Read back like any input: a file edited by hand or written by a build without these checks
    // must not come back as the reach's model.
    std::string problem = PersistedModelProblem(model, (*reach)->pipeline().model_bounds());
    // A kind the reach no longer identifies (batch_models changed) is not its model any more.
    const core::ReachSampleProcessorOptions& o = (*reach)->pipeline().options();
    const bool configured =
        model.model_kind == "id" ? o.batch_id
        : model.model_kind == "idz"
            ? o.batch_idz.has_value()
            : std::any_of(o.batch_process_models.begin(), o.batch_process_models.end(),
                          [&](core::ProcessBatchKind k) {
                            return core::ProcessBatchKindName(k) == model.model_kind;
                          });
    if (problem.empty() && !configured) {
      problem = "kind " + model.model_kind + " is not in the reach's batch_models";
    }
    if (!problem.empty()) {
      LogWarning("state: " + store.PathFor(model.reach, model.model_kind).string() + ": reach " +
                 model.reach + ": " + problem + "; ignored");
      continue;
    }
    publisher.PublishModelJson(model.reach, model.model, WallNowS());
    LogInfo("reach " + model.reach + ": resumed the persisted " + model.model_kind + " model " +
            model.model.dump());
  }
}

PersistedModel MakePersistedModel(const ReachRuntime& reach,
                                  const core::IntegratorDelayIdentification& result,
                                  double wall_time_s) {
  PersistedModel model;
  model.reach = reach.name();
  model.model_kind = "id";
  model.saved_utime_us = ToUtime(wall_time_s);
  model.model = drivers::ToJson(result);
  if (const core::OnlineIntegratorDelayBank* bank = reach.pipeline().online_id()) {
    const core::IntegratorDelaySnapshot s = bank->Snapshot();
    model.online = {{"delay_s", s.delay_s},
                    {"area_m2", s.area_m2},
                    {"b", s.b},
                    {"area_std_m2", s.area_std_m2},
                    {"samples", bank->health().samples}};
  }
  return model;
}

std::size_t BatchModelCount(const std::vector<std::unique_ptr<ReachRuntime>>& reaches) {
  std::size_t count = 0;
  for (const auto& reach : reaches) {
    const core::ReachSampleProcessorOptions& o = reach->pipeline().options();
    count += (o.batch_id ? 1U : 0U) + (o.batch_idz ? 1U : 0U) + o.batch_process_models.size();
  }
  return count;
}

}  // namespace canalid::daemon
