#!/usr/bin/env bash
# Plants known bugs one at a time and checks that the test suite catches
# each: the bugs a reviewer planted for issue 10, and variants of them.
# For every mutant: the source is changed (a literal text replacement that
# must match exactly once), the test targets the mutant names are rebuilt
# in build/ (the same build for every mutant, so only the mutated file
# recompiles), the named tests run through ctest-strict.sh (so a skip
# counts as caught, as in scripts/test.sh), and the source is restored.
# Prints one line per mutant and exits non-zero if any mutant survived,
# does not compile, or names text that is no longer in its file.
#   bash scripts/mutants.sh            # all mutants
#   bash scripts/mutants.sh flip rot   # only those whose name contains a word
#   bash scripts/mutants.sh --check    # only that every entry still matches
#   bash scripts/mutants.sh --changed [BASE]
#       # only the mutants a change since BASE can affect (CI runs this;
#       # docs/development.md gives the rule and how BASE is chosen)
# Needs a configured build/ (bash scripts/build.sh) and a clean tree for the
# files it touches.
set -uo pipefail
cd "$(dirname "$0")/.."
[ -f build/CMakeCache.txt ] || { echo "mutants: run bash scripts/build.sh first" >&2; exit 2; }

# name | file | text | replacement | ctest -R regex
# (\n in text/replacement is a newline)
mutants=$(cat <<'LIST'
scheer_attenuation_linear|shaders/ao_main.frag.glsl|(1.0 + u_c * l * l)|(1.0 + u_c * l)|^test_ao$
scheer_attenuation_cubic|shaders/ao_main.frag.glsl|(1.0 + u_c * l * l)|(1.0 + u_c * l * l * l)|^test_ao$
scheer_no_cosine_bias|shaders/ao_main.frag.glsl|(cosv - u_bias) / (1.0 - u_bias)|cosv|^test_ao$
mask_threshold_0.5|shaders/ao_main.frag.glsl|.r > 1.5;|.r > 0.5;|^test_ao$
mask_threshold_2.5|shaders/ao_main.frag.glsl|.r > 1.5;|.r > 2.5;|^test_ao$
flip_guard_off|lib/track/pose.c|        if (have_prev) {\n            double a = mr_pose_angle_deg(&cm, &prev_cfw);|        if (0) {\n            double a = mr_pose_angle_deg(&cm, &prev_cfw);|^test_track
ambiguity_ratio_10|lib/track/pose.c|p.ambiguity_ratio : 2.5;|p.ambiguity_ratio : 10.0;|^test_track
rot_beta_dropped|lib/track/filter.c|f->p.rot_min_cutoff + f->p.rot_beta * f->dr_hat|f->p.rot_min_cutoff|^test_track
beta_dropped|lib/track/filter.c|f->p.min_cutoff + f->p.beta * sqrt(speed)|f->p.min_cutoff|^test_track
rot_jump_reset_removed|lib/track/filter.c|mr_pose_angle_deg(raw, &f->raw_last) > f->p.jump_deg|0|^test_track
rot_jump_40deg|lib/track/filter.c|p.jump_deg = or_default(p.jump_deg, MR_FILTER_DEFAULT_JUMP_DEG);|p.jump_deg = or_default(p.jump_deg, 40.0);|^test_track
gap_reset_removed|lib/track/filter.c|dt > f->p.max_gap_s)) reset = true;|dt > 1e9)) reset = true;|^test_track
prev_pose_age_inclusive|lib/track/tracker.c|age >= 0 && age < t->prev_max_age_s|age >= 0 && age <= t->prev_max_age_s|^test_track
prev_pose_always|lib/track/tracker.c|t->prev.valid && age >= 0 && age < t->prev_max_age_s|t->prev.valid && age == age|^test_track
prev_pose_backwards|lib/track/tracker.c|age >= 0 && age < t->prev_max_age_s|age < t->prev_max_age_s|^test_track
annotation_folder_not_synced|lib/session/annotations.c|    bool existed = mr_file_exists(path);|    bool existed = true;|^test_session$
replay_seek_time_strict|lib/session/replay.c|if (r->frames[mid].t <= t) lo = mid + 1;|if (r->frames[mid].t < t) lo = mid + 1;|^test_session$
lod_one_sided_ab|lib/scene/lod.c|r = dmax(ab, ba);|r = ab; (void)ba;|^test_cull_lod$
lod_one_sided_ba|lib/scene/lod.c|r = dmax(ab, ba);|r = ba; (void)ab;|^test_cull_lod$
atomic_write_in_place|lib/core/file.c|snprintf(tmp, sizeof tmp, "%s.tmp.%ld", path, (long)getpid())|snprintf(tmp, sizeof tmp, "%s", path)|^test_core$
atomic_temp_left|lib/core/file.c|        int e = errno;\n        remove(tmp);\n        return mr_fail(err, MR_ERR_IO, "cannot write %s: %s", path, strerror(e));\n    }\n    if|        int e = errno;\n        return mr_fail(err, MR_ERR_IO, "cannot write %s: %s", path, strerror(e));\n    }\n    if|^test_core$
touch_target_px|lib/ui/widgets.c|ceilf(mr_ui_mm(ui, ui->p.min_target_mm))|ceilf(ui->p.min_target_mm)|^test_ui$
touch_target_px_in_view|lib/ui/widgets.c|ceilf(mr_ui_mm(ui, ui->p.min_target_mm))|ceilf(ui->p.min_target_mm)|^cli_view$
overlay_p1_p2_swapped|shaders/overlay.frag.glsl|p1 = u_dist[2], p2 = u_dist[3]|p1 = u_dist[3], p2 = u_dist[2]|^test_render$
overlay_p2_sign|shaders/overlay.frag.glsl|2.0 * p1 * xy.x * xy.y + p2 * (r2|2.0 * p1 * xy.x * xy.y - p2 * (r2|^test_render$
view_act_on_press|lib/ui/widgets.c|bool clicked = enabled && ui->released && ui->active == id && over;|bool clicked = enabled && ui->pressed && over;|^test_view$
view_slide_off_acts|lib/ui/widgets.c|bool clicked = enabled && ui->released && ui->active == id && over;|bool clicked = enabled && ui->released && ui->active == id;|^test_view$
view_ao_cycle_backwards|lib/view/controller.c|v->s.ao = (mr_ao_method)next_method("ao", (int)v->s.ao, MR_AO_NONE);|v->s.ao = (mr_ao_method)((v->s.ao + MR_AO_METHOD_COUNT - 1) % MR_AO_METHOD_COUNT);|^test_view$
view_settings_in_place|lib/view/settings.c|    bool ok = (!dir[0] |    FILE *fo = fopen(path, "wb");\n    char *txt = cJSON_Print(j);\n    if (fo && txt) fputs(txt, fo);\n    if (fo) fclose(fo);\n    free(txt);\n    bool ok = true;\n    if (0) ok = (!dir[0] |^test_view$
view_lost_fades_to_model|lib/view/controller.c|1.0f - (1.0f - s->alpha) * 0.35f|s->alpha * 0.35f|^test_view$
view_layout_drops_first|lib/view/controller.c|        if (i >= shown) {|        if (i < n - shown) {|^test_view$
gl_context_4.9|lib/render/gpu.c|EGL_CONTEXT_MINOR_VERSION, 5,|EGL_CONTEXT_MINOR_VERSION, 9,|^(test_render|cli_render)$
gl_target_leaks_positions|lib/render/gl_util.c|glDeleteTextures((GLsizei)(sizeof t->color / sizeof t->color[0]), t->color);|glDeleteTextures(3, t->color);|^test_gl_objects$
ao_reuse_never|lib/render/pass_ao.c|return memcmp(&key, &s->last, sizeof key) == 0 ? AO_PLAN_REUSE : AO_PLAN_RUN;|(void)key; return AO_PLAN_RUN;|^test_ao$
registry_gbuffer_skipped|lib/render/passes.c|.name = "gbuffer", .prepare|.name = "gbuffer", .needed = mr_pass_need_overlay, .prepare|^test_render$
ghost_hidden_in_gbuffer|lib/render/passes.c|!(f->writing & RES(RES_HIDDEN_DEPTH))|true|^test_ghost$
opt_default_outside_range|lib/render/options.c|1, MR_AO_MAX_SAMPLES, MR_AO_DEFAULT_SAMPLES|1, MR_AO_MAX_SAMPLES, 0|^test_options$
opt_default_not_the_macro|lib/render/options.c|GH(tc_silhouette), 0, 4, MR_GHOST_DEFAULT_TC_SILHOUETTE|GH(tc_silhouette), 0, 4, MR_GHOST_DEFAULT_TC_MINIMAL|^test_options$
opt_wrong_offset|lib/render/options.c|{"rmin", MR_OPT_FLOAT, AO(r_min)|{"rmin", MR_OPT_FLOAT, AO(r_max)|^test_options$
opt_wrong_offset_untabled|lib/render/options.c|GH(curv_scale)|GH(saliency_gain)|^test_options$
opt_range_off_by_one|lib/render/options.c|AO(blur_radius), 0, 32,|AO(blur_radius), 0, 33,|^test_options$
opt_upper_bound_exclusive|lib/core/options.c|v > o->hi) return range_fail(o, text, err);\n        store(o, params, to_field(o, (double)v));|v >= o->hi) return range_fail(o, text, err);\n        store(o, params, to_field(o, (double)v));|^test_options$
opt_cli_value_ignored|lib/core/cli.c|if (mr_opt_set_row(o, t->params, v, &err)) continue;|if (mr_opt_set_row(o, t->params, v, &err) + 1) continue;|^cli_options$
replay_meta_markers_key|lib/session/replay.c|cJSON_GetObjectItemCaseSensitive(meta, "markers") : NULL;|cJSON_GetObjectItemCaseSensitive(meta, "marker") : NULL;|^test_session$
opt_zero_default_user_zero_is_default|lib/core/options.c|(o->flags & MR_OPT_ZERO_DEFAULT) && v == 0 ? -1 : v;|(o->flags & MR_OPT_ZERO_DEFAULT) && v < 0 ? -1 : v;|^test_options$
opt_detector_refine_default_off|lib/track/options.c|DT(refine_edges), 0, 1, 1,|DT(refine_edges), 0, 1, 0,|^test_options$
track_opts_only_threads|app/track_util.c|tp.detector = *dp;|tp.detector.threads = dp->threads;|^cli_options$
study_consistence_half|lib/study/stats.c|- ss / 2.0;|- ss / 3.0;|^test_study$
study_agreement_offset|lib/study/stats.c|return 2.0 * tau / max_tau - 1.0;|return 2.0 * tau / max_tau;|^test_study$
study_binom_threshold|lib/study/stats.c|if (mr_study_binom_upper_tail(n, k) < alpha) return k;|if (mr_study_binom_upper_tail(n, k + 1) < alpha) return k;|^test_study$
study_davidson_tie_feature|lib/study/stats.c|{0.5, 0.5, 1}};|{1.0, 0.5, 1}};|^test_study$
study_mm_update|lib/study/stats.c|ng[i] = d > 0 ? W[i] / d : g[i];|ng[i] = d > 0 ? (W[i] + 0.1) / d : g[i];|^test_study$
study_no_pseudo_count|lib/study/stats.c|    if (mr_study_graph_connected(w, ties, t, &who)) return;|    if (1) return;|^test_study$
study_se_not_centred|lib/study/stats.c|S[i * t + i] - 2 * row[i] + tot|S[i * t + i]|^test_study$
study_no_indifference_baseline|lib/study/stats.c|return fmin(1.0, have ? num / den : num);|return fmin(1.0, num);|^test_study$
study_plan_not_shuffled|lib/study/plan.c|    for (int i = n - 1; i > 0; i--) {|    for (int i = n - 1; i > n; i--) {|^test_study$
study_repeat_answer_kept|lib/study/votes.c|} else if (seen(out, &v)) {|} else if (seen(out, &v) && 0) {|^test_study$
study_resume_skips_one|lib/study/votes.c|        if (!answered[k]) return k;|        if (!answered[k]) return k + 1;|^test_study$
study_no_fixation|lib/study/run.c|>= plan->fixation_ms|>= 0|^test_study$
core_parallel_one_thread|lib/core/parallel.c|    if (nt < 1) nt = 1;|    nt = 1;|^test_core$
core_parallel_stop_ignored|lib/core/parallel.c|            q->stopped = true;|            q->stopped = false;|^test_core$
study_gg_epsilon|lib/study/infer.c|o->eps_gg = tr2 > 0 ? tr * tr / (q * tr2) : 1.0;|o->eps_gg = tr2 > 0 ? tr * tr / tr2 : 1.0;|^test_study_stats$
study_mauchly_plain_p|lib/study/infer.c|p0 + w2 * (p4 - p0)|p0 + 0 * w2 * (p4 - p0)|^test_study_stats$
study_wilcoxon_lower_tail|lib/study/infer.c|if (s <= w) lo += c[s];|if (s < w) lo += c[s];|^test_study_stats$
study_holm_not_monotone|lib/study/infer.c|run = fmax(run, fmin(1.0, p[ord[k]] * (m - k)));|run = fmin(1.0, p[ord[k]] * (m - k));|^test_study_stats$
study_friedman_no_tie_correction|lib/study/infer.c|o->chi2 = corr > 0 ? chi / corr : NAN;|o->chi2 = corr > 0 ? chi : NAN;|^test_study_stats$
study_eq56_clamped|lib/study/stats.c|return (neutral_distinct / n_per_pair) / (neutral_identical / n_identical);|return fmin(1.0, (neutral_distinct / n_per_pair) / (neutral_identical / n_identical));|^test_study_designs$
study_scenes_not_alternating|lib/study/plan.c|int s = b == 1 ? sI : b == 2 ? sII : q < half ? sI : sII;|int s = b == 1 ? sI : b == 2 ? sI : q < half ? sI : sII;|^test_study_designs$
study_no_exclusion|lib/study/analyze.c|if (!out) kept.v[kept.count++] = votes->v[i];|kept.v[kept.count++] = votes->v[i];|^test_study_designs$
study_no_break|lib/study/run.c|r->in_break = !done(r) && r->fixation && r->shown_block|r->in_break = false && r->shown_block|^test_study_designs$
study_tap_units|lib/study/analyze_rt.c|eu = epx * k->units_per_px;|eu = epx;|^test_study_designs$
study_overall_rotation|lib/study/run.c|answered = true, answer = (t->right + i) % n;|answered = true, answer = i;|^test_study_designs$
gltf_sparse_values_at_index_offset|lib/scene/gltf_io.cc|        vp += sp.values.byteOffset;|        vp += sp.indices.byteOffset;|^test_gltf_ext$
gltf_sparse_short_32768|lib/scene/gltf_io.cc|return norm ? std::max(v / 32767.0, -1.0) : (double)v;|return norm ? std::max(v / 32768.0, -1.0) : (double)v;|^test_gltf_ext$
bcf_viewpoint_guid_is_topic|lib/export/findings.c|mr_bcf_guid(key, n, 2, f->viewpoint_guid);|mr_bcf_guid(key, n, 1, f->viewpoint_guid);|^test_export$
bcf_fov_not_fitted|lib/export/bcf.c|double fit = fmin(fmax(fov, 45.0), 60.0);|double fit = fov;|^test_export$
bcf_no_ifcguid|lib/export/bcf.c|if (mr_ifc_guid_valid(c->ifc_guid)) mr_xml_attr(x, "IfcGuid", c->ifc_guid);|(void)0;|^test_export$
bcf_21_hints_missing|lib/export/bcf.c|if (!v3) setup_hints(x, v);|if (0) setup_hints(x, v);|^test_export$
mark_element_guid_lost|lib/session/annotations.c|cJSON_AddStringToObject(e, "guid", a->element_guid);|cJSON_AddStringToObject(e, "guid", "");|^test_export$
bcf_xml_doctype_read|lib/export/xml_read.c|starts(r, "<!DOCTYPE")|starts(r, "<!NOPE")|^test_bcf_read$
bcf_dotdot_allowed|lib/export/bcf_read.c|p[0] == '.' && p[1] == '.')|p[0] == '.' && p[1] == 'X')|^test_bcf_read$
bcf_entry_uncapped|lib/export/bcf_read.c|            if (n > cap) {|            if (0) {|^test_bcf_read$
bcf_30_color_components|lib/export/bcf_read.c|if (!components_in(list ? list : e, &cc->items, &cc->count)) return false;|if (!components_in(e, &cc->items, &cc->count)) return false;|^test_bcf_read$
bcf_answer_status_kept|lib/export/bcf_answer.c|if (a->status && a->status[0]) snprintf|if (0) snprintf|^test_bcf_read$
element_describe_no_storey|lib/scene/element.c|if (e && e->storey >= 0 && e->storey < s->storey_count) ADD|if (0) ADD|^test_ifc$
study_cmax_odd_even_formula|lib/study/stats.c|(t % 2) ? (td * td * td - td) / 24.0|(t % 2) ? (td * td * td - 4 * td) / 24.0|^test_study$
map_huber_scale_unweighted|lib/track/map_ba.cc|ceres::HuberLoss loss2(loss_px * w);|ceres::HuberLoss loss2(loss_px);|^test_map$
map_control_residual_sign|lib/track/map.c|cr->residual[1] = pr.y - p->controls[q].world.y;|cr->residual[1] = p->controls[q].world.y - pr.y;|^test_map$
map_control_loo_sign|lib/track/map.c|cr->loo[1] = pr.y - p->controls[q].world.y;|cr->loo[1] = p->controls[q].world.y - pr.y;|^test_map$
shadow_cascade_ratio_8|lib/render/pass_shadow.c|log(vis_far / vis_near) / log(CASCADE_RATIO)|log(vis_far / vis_near) / log(8.0)|^test_rules$
shadow_cascade_unclamped|lib/render/pass_shadow.c|return n < 1 ? 1 : n > MR_SHADOW_MAX_CASCADES ? MR_SHADOW_MAX_CASCADES : n;|return n < 1 ? 1 : n;|^test_rules$
shadow_cascade_atlas_unchecked|lib/render/pass_shadow.c|2 * (long)map_size > (long)max_tex) return 1;|2 * (long)map_size > 4 * (long)max_tex) return 1;|^test_rules$
hlod_bound_no_simplification_error|lib/scene/hlod.c|n->error = e_in + h_err + rounding;|n->error = e_in + rounding;|^test_hlod$
hlod_cut_unprojected|lib/scene/hlod.c|n->error * (p->fmax / zmin) <= p->pixels|n->error * p->fmax <= p->pixels|^test_hlod$
hlod_cache_index_unchecked|lib/scene/hlod.c|if (n->indices[k] >= n->vertex_count) return false;|if (n->indices[k] > 0xffffffffu) return false;|^test_hlod$
hlod_draw_one_id_per_proxy|lib/render/hlod_draw.c|gi->ids[0] = (uint32_t)q->node + 1;|gi->ids[0] = (uint32_t)hn->runs[0].node + 1;|^test_hlod_draw$
hlod_draw_all_layers|lib/render/hlod_draw.c|cp.layers = vw->layers;|cp.layers = 3;|^test_hlod_draw$
replay_stop_ignored|lib/batch/replay.c|if (mr_stop_requested()) {|if (false) {|^(test_batch|cli_batch_stop)$
replay_no_index_after_stop|lib/batch/replay.c|    if (written > 0) {|    if (written > 0 && !st->interrupted) {|^cli_batch_stop$
outdir_not_refused|lib/core/stop.c|if (!force && mr_dir_has_entries(path))|if (0)|^cli_batch_stop$
outdir_left_after_failure|lib/batch/replay.c|    if (written == 0) mr_outdir_abandon(od);|    (void)od;|^test_batch$
hall_mkdir_before_checks|lib/session/hall.c|    bool ok = true;\n    for (int i = 0; ok && i < MR_HALL_ITEM_COUNT; i++)|    bool ok = mr_mkdirs(dir, err);\n    for (int i = 0; ok && i < MR_HALL_ITEM_COUNT; i++)|^test_hall$
hall_plan_not_relative|lib/session/hall.c|            relative_to(dir, u->files[i], rel, sizeof rel);|            relative_to(dir, u->files[i], rel, sizeof rel), snprintf(rel, sizeof rel, "%s", u->files[i]);|^test_hall$
hall_marks_next_to_recording|lib/session/hall_args.c|    if (mr_hall_contains(h, session)) {|    if (1) {|^test_hall$
hall_no_unknown_key_warning|lib/session/hall.c|    if (warn) mr_json_warn_unknown(j, k_known, file);|    (void)warn, (void)k_known;|^cli_hall$
help_research_not_apart|lib/core/cli.c|for (; o->name && o->name[0]; o++) print_row(o->name, o->arg, o->help);|for (; o->name; o++) if (o->name[0]) print_row(o->name, o->arg, o->help);|^cli_help$
triangulate_sigma_over_sqrt3|lib/track/triangulate.c|out->sigma = sqrt(fmax(0, out->cov[0] + out->cov[4] + out->cov[8]));|out->sigma = sqrt(fmax(0, out->cov[0] + out->cov[4] + out->cov[8]) / 3);|^test_sigma$
triangulate_line_sigma_over_sqrt3|lib/track/triangulate.c|*sigma = sqrt(fmax(v, 0));|*sigma = sqrt(fmax(v, 0) / 3);|^test_sigma$
triangulate_point_sigma_not_per_axis|lib/track/triangulate.c|*sigma = sqrt((t->cov[0] + t->cov[4] + t->cov[8]) / 3);|*sigma = sqrt(t->cov[0] + t->cov[4] + t->cov[8]);|^test_sigma$
map_lost_tag_not_replaced|lib/track/map.c|        bool used = false, posed = false;|        bool used = true, posed = false;|^test_bench$
cluster_key_positions_dropped|lib/render/cluster_cache.c|    h = mr_hash64(h, positions, (size_t)vertex_count * 12);|    h = mr_hash64(h, positions, 0);|^test_rules$
cluster_key_index_quarter|lib/render/cluster_cache.c|return mr_hash64(h, indices, (size_t)count * 4);|return mr_hash64(h, indices, (size_t)count);|^test_rules$
cluster_key_threshold_dropped|lib/render/cluster_cache.c|uint32_t threshold) {\n    uint64_t h|uint32_t threshold_) {\n    uint32_t threshold = 0 * threshold_;\n    uint64_t h|^test_rules$
LIST
)

# --check: only verify that every mutant's text is in its file exactly once
# (no build, seconds): a stale entry fails, it is never skipped.
if [ "${1:-}" = --check ]; then
  bad=0
  while IFS='|' read -r name file text repl tests; do
    [ -n "$name" ] || continue
    if ! FROM="$text" perl -0ne '
          my $f = $ENV{FROM} =~ s/\\n/\n/gr;
          my $n = () = /\Q$f\E/g;
          exit($n == 1 ? 0 : 1);' "$file" 2>/dev/null; then
      echo "ERROR    $name: the text to mutate in $file is not there exactly once (update the list)"
      bad=$((bad + 1))
    fi
  done <<<"$mutants"
  echo "mutants --check: $bad stale of $(grep -c . <<<"$mutants")"
  [ $bad -eq 0 ]
  exit
fi

# --changed [BASE]: the mutants a change since BASE can affect. BASE is the
# argument, else $MR_MUTANTS_BASE, else the commit in .ci/mutants-base (the
# last commit CI passed on, recorded by whoever lands a green CI run). The
# change is git diff from merge-base(BASE, HEAD) to the working tree. A
# mutant runs when its file changed, when a test its regex names changed
# (tests/NAME.c or .sh: a weakened test must still catch it), or when its
# own line in this list is new or edited. Every mutant runs when a shared
# header changed (lib/*/mr_*.h, lib/*/*_internal.h, tests/mr_test*.h, a
# shader include: shaders/NAME.h or NAME.glsl without a stage), and when
# BASE is not in this clone's history (a shallow clone, a rewritten main):
# running more is safe, fewer is not.
only=""
if [ "${1:-}" = --changed ]; then
  base=${2:-${MR_MUTANTS_BASE:-$(cat .ci/mutants-base 2>/dev/null || true)}}
  base=${base%%[[:space:]]*}
  if [ -z "$base" ] || ! git cat-file -e "$base^{commit}" 2>/dev/null || ! mb=$(git merge-base "$base" HEAD 2>/dev/null); then
    echo "mutants: base '${base:-none}' is not in this clone's history: running every mutant"
    only=all
  else
    changed=$( { git diff --name-only "$mb"; git ls-files --others --exclude-standard; } | sort -u)
    echo "mutants: changes since ${base:0:12} (merge-base ${mb:0:12}): $(grep -c . <<<"$changed" || true) file(s)"
    if grep -qE '^(lib/[^/]+/mr_[^/]+\.h|lib/[^/]+/[^/]+_internal\.h|tests/mr_test[^/]*\.h|shaders/[^/.]+\.(h|glsl))$' <<<"$changed"; then
      echo "mutants: a shared header changed: running every mutant"
      only=all
    else
      newlines=$(git diff "$mb" -- scripts/mutants.sh | sed -n 's/^+\([^+|][^|]*\)|.*/\1/p')
      while IFS='|' read -r name file text repl tests; do
        [ -n "$name" ] || continue
        hit=0
        grep -qxF -- "$file" <<<"$changed" && hit=1
        grep -qxF -- "$name" <<<"$newlines" && hit=1
        for t in $(grep -oE '(test|cli|fuzz)_[A-Za-z0-9_]+' <<<"$tests"); do
          grep -qxE "tests/$t\.(c|cc|sh)" <<<"$changed" && hit=1
        done
        [ $hit -eq 1 ] && only="$only $name"
      done <<<"$mutants"
      [ -n "$only" ] || { echo "mutants: no mutant's file, test or entry changed: nothing to run"; exit 0; }
      echo "mutants: to run:$only"
    fi
  fi
  set --
  [ -z "${MR_MUTANTS_DRY:-}" ] || exit 0
fi

backup=$(mktemp -d)
current=""
restore() {
  if [ -n "$current" ]; then cp "$backup/orig" "$current"; current=""; fi
}
trap 'restore; rm -rf "$backup"' EXIT
trap 'exit 130' INT TERM

survived=0 caught=0 built=""
start=$(date +%s)
while IFS='|' read -r name file text repl tests; do
  [ -n "$name" ] || continue
  if [ -n "$only" ] && [ "$only" != all ]; then
    [[ " $only " == *" $name "* ]] || continue
  fi
  if [ $# -gt 0 ]; then
    want=0
    for w in "$@"; do case $name in *"$w"*) want=1 ;; esac; done
    [ $want -eq 1 ] || continue
  fi
  if ! git diff --quiet -- "$file"; then echo "mutants: $file has uncommitted changes; commit them first" >&2; exit 2; fi
  cp "$file" "$backup/orig"
  current=$file
  if ! FROM="$text" TO="$repl" perl -0pi -e '
        my ($f, $t) = map { s/\\n/\n/gr } ($ENV{FROM}, $ENV{TO});
        my $n = () = /\Q$f\E/g;
        die "matches $n times, want 1\n" unless $n == 1;
        s/\Q$f\E/$t/;' "$file"; then
    echo "ERROR    $name: the text to mutate in $file is not there exactly once (update the list)"
    restore
    survived=$((survived + 1))
    continue
  fi
  # Build only what the named tests run when the regex names them exactly
  # (^name$ or ^(a|b)$; cli_* scripts run mrcheck); otherwise everything.
  targets=""
  if [[ $tests =~ ^\^\(?([A-Za-z0-9_|]+)\)?\$$ ]]; then
    for t in ${BASH_REMATCH[1]//|/ }; do
      case $t in
        cli_* | module_map | header_alone_*) targets="$targets mrcheck" ;;
        *) targets="$targets $t" ;;
      esac
    done
    # test_track_retrack runs the binary too (tests/CMakeLists.txt)
    [[ " $targets " == *" test_track_retrack "* ]] && targets="$targets mrcheck"
  fi
  if [ -n "$targets" ]; then build_args=(--target $targets); else build_args=(); fi
  built="$built ${targets:-all}"
  if ! cmake --build build -j"$(nproc)" "${build_args[@]}" >"$backup/build.log" 2>&1; then
    echo "ERROR    $name: the mutant does not compile"
    tail -n 5 "$backup/build.log"
    restore
    survived=$((survived + 1))
    continue
  fi
  if bash scripts/ctest-strict.sh build -R "$tests" >"$backup/test.log" 2>&1; then
    echo "SURVIVED $name ($file): tests '$tests' still pass"
    survived=$((survived + 1))
  else
    why=$(grep -E "CHECK failed|FAIL:|FAILED|SKIPPED" "$backup/test.log" | cut -c1-200 | head -n 3 | paste -sd "|" -)
    echo "caught   $name: $why"
    caught=$((caught + 1))
  fi
  restore
done <<<"$mutants"

# A hidden EGL (no vendor library) must fail the suite, not skip it.
if { [ $# -eq 0 ] && { [ -z "$only" ] || [ "$only" = all ] || [[ " $only " == *" gl_"* ]]; }; } || [[ " $* " == *" egl"* ]]; then
  if __EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent bash scripts/ctest-strict.sh build -R '^(test_render|cli_render)$' >"$backup/test.log" 2>&1; then
    echo "SURVIVED egl_hidden: the suite passes without EGL"
    survived=$((survived + 1))
  else
    echo "caught   egl_hidden: $(grep -m1 -E "FAILED|SKIPPED" "$backup/test.log" | cut -c1-200)"
    caught=$((caught + 1))
  fi
fi

# Rebuild what was built from a mutant (the restored sources are newer).
echo "rebuilding the unmutated tree ..."
if [[ " $built " == *" all "* ]] || [ -z "$built" ]; then
  cmake --build build -j"$(nproc)" >/dev/null 2>&1
else
  # shellcheck disable=SC2086
  cmake --build build -j"$(nproc)" --target $(tr ' ' '\n' <<<"$built" | sort -u | paste -sd ' ') >/dev/null 2>&1
fi
echo "mutants: $caught caught, $survived survived or broken ($(($(date +%s) - start)) s)"
[ $survived -eq 0 ]
