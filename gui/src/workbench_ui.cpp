#include "geoanchor/gui/workbench_ui.hpp"

#include <imgui.h>

#include <algorithm>
#include <cstring>
#include <filesystem>

#include "geoanchor/base/error.hpp"
#include "ui_common.hpp"

namespace geoanchor::gui {

using detail::col4;
using detail::panel;

std::string_view to_string(View v) {
  switch (v) {
    case View::workbench: return "workbench";
    case View::plan: return "plan";
    case View::histogram: return "histogram";
    case View::table: return "table";
    case View::parameters: return "parameters";
    case View::comparison: return "comparison";
  }
  return "?";
}

std::optional<View> view_from_string(std::string_view name) {
  for (View v : kAllViews) {
    if (to_string(v) == name) return v;
  }
  return std::nullopt;
}

Eigen::Vector2d PlanGeometry::pixel_of(const Eigen::Vector2d& en_m) const {
  const Eigen::Vector2d c(0.5 * (left + right), 0.5 * (top + bottom));
  return c + px_per_m * Eigen::Vector2d(en_m.x() - center_en_m.x(), -(en_m.y() - center_en_m.y()));
}

float HistogramGeometry::x_of(double w) const {
  const double span = kHistogramBinWidth * static_cast<double>(counts.size());
  return left + static_cast<float>((w - w_low) / span) * (right - left);
}

void TextAudit::check(std::string_view text, std::string_view where, float x0, float y0, float x1, float y1, float cx0, float cy0,
                      float cx1, float cy1, bool vertical) {
  constexpr float kSlack_px = 0.5f;  // vertex positions round to the pixel grid
  drawn.push_back({std::string(text), std::string(where), x0, y0, x1, y1});
  if (x0 < cx0 - kSlack_px || x1 > cx1 + kSlack_px) {
    clipped.push_back({std::string(text), std::string(where), x1 - x0, std::max(0.0f, std::min(x1, cx1) - std::max(x0, cx0)), false});
  } else if (vertical && (y0 < cy0 - kSlack_px || y1 > cy1 + kSlack_px)) {
    clipped.push_back({std::string(text), std::string(where), y1 - y0, std::max(0.0f, std::min(y1, cy1) - std::max(y0, cy0)), true});
  }
}

void TextAudit::check_width(std::string_view text, std::string_view where, float needed_px, float available_px) {
  constexpr float kSlack_px = 0.5f;
  drawn.push_back({std::string(text), std::string(where), 0.0f, 0.0f, needed_px, 0.0f});
  if (needed_px > available_px + kSlack_px) clipped.push_back({std::string(text), std::string(where), needed_px, available_px, false});
}

WorkbenchUi::WorkbenchUi(WorkbenchModel& model, UiOptions options) : model_(model), options_(std::move(options)) {
  const std::size_t n = std::min(options_.save_path.size(), save_path_.size() - 1);
  std::memcpy(save_path_.data(), options_.save_path.data(), n);
}

void WorkbenchUi::configure_context(float display_height_px) {
  namespace fs = std::filesystem;
  static const char* kRegular = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  static const char* kBold = "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf";
  for (const char* f : {kRegular, kBold}) {
    // Debian's ImGui keeps IM_ASSERT: a missing font would abort, so check first.
    if (!fs::is_regular_file(f)) {
      throw Error(ErrorKind::io, "E_FONT", std::string(f) + ": font missing (Debian package fonts-dejavu-core; run scripts/setup.sh)");
    }
  }
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // no saved window state: every frame from the same inputs is the same
  io.LogFilename = nullptr;
  // Latin-1, Greek (σ, χ, Δ), modifier letters (the ᵀ of vᵀPv),
  // punctuation (–, …, ′, ″), super- and subscripts, arrows, mathematical
  // operators (±, ≤, ≈) and shapes (■, ▲, ●, ○).
  static const ImWchar kRanges[] = {0x0020, 0x00FF, 0x0370, 0x03FF, 0x1D2C, 0x1D6A, 0x2000, 0x206F, 0x2070, 0x209F,
                                    0x2190, 0x21FF, 0x2200, 0x22FF, 0x25A0, 0x25FF, 0};
  const float px = std::clamp(std::round(display_height_px / 55.0f), 13.0f, 24.0f);
  io.Fonts->Clear();
  io.Fonts->AddFontFromFileTTF(kRegular, px, nullptr, kRanges);
  io.Fonts->AddFontFromFileTTF(kBold, px, nullptr, kRanges);

  ImGui::StyleColorsLight();
  ImGuiStyle& s = ImGui::GetStyle();
  s.WindowRounding = 0.0f;
  s.FrameRounding = 2.0f;
  s.WindowBorderSize = 1.0f;
  s.WindowPadding = ImVec2(px * 0.5f, px * 0.4f);
  s.CellPadding = ImVec2(px * 0.3f, px * 0.1f);
  s.Colors[ImGuiCol_WindowBg] = col4(palette::kBackground);
  s.Colors[ImGuiCol_PopupBg] = col4(palette::kBackground);
  s.Colors[ImGuiCol_Text] = col4(palette::kInk);
  s.Colors[ImGuiCol_TitleBg] = col4(palette::kPanel);
  s.Colors[ImGuiCol_TitleBgActive] = col4(palette::kPanel);
  s.Colors[ImGuiCol_TitleBgCollapsed] = col4(palette::kPanel);
}

void WorkbenchUi::refresh() {
  model_.poll();
  if (model_.generation() == shown_generation_) return;
  shown_generation_ = model_.generation();
  rows_ = model_.rows();
  resort_ = true;
}

namespace {

const char* panel_title(View v) {
  switch (v) {
    case View::plan: return "Plan (ENU at the network centroid)";
    case View::histogram: return "Standardized residuals (w-tests)";
    case View::table: return "Points";
    case View::parameters: return "Parameters";
    case View::comparison: return "Model comparison";
    case View::workbench: return "geoanchor workbench";
  }
  return "";
}

}  // namespace

void WorkbenchUi::draw(View view, float width, float height) {
  refresh();
  plan_.drawn = false;
  histogram_.drawn = false;
  table_.drawn = false;
  audit_ = TextAudit{};
  composite_ = view == View::workbench;
  const auto body = [this](View v) {
    return [this, v] {
      // A refused fit leaves every view with the reason only.
      if (!model_.fit() && v != View::table && v != View::comparison) {
        detail::wrapped_coloured(audit_, palette::kOutlier, "No fit: " + model_.error(), std::string(to_string(v)) + ": no fit");
        return;
      }
      switch (v) {
        case View::plan: draw_plan(); break;
        case View::histogram: draw_histogram(); break;
        case View::table: draw_table(); break;
        case View::parameters: draw_parameters(); break;
        case View::comparison: draw_comparison(); break;
        case View::workbench: break;
      }
    };
  };
  if (view != View::workbench) {
    panel(audit_, panel_title(view), 0, 0, width, height, body(view));
    return;
  }
  // The bar's height is what its contents took in the last frame (they
  // flow onto more lines in a narrow window).
  const float font = ImGui::GetFontSize();
  const float bar_h = bar_height_px_ > 0.0f ? bar_height_px_ : std::round(font * 4.2f);
  panel(audit_, "geoanchor workbench", 0, 0, width, bar_h, [this] {
    draw_bar();
    bar_height_px_ = std::ceil(ImGui::GetCursorPosY() + ImGui::GetStyle().WindowPadding.y - ImGui::GetStyle().ItemSpacing.y);
  });
  // Upper row: plan, histogram, parameters; lower row: the table and the comparison.
  const float upper = std::round((height - bar_h) * 0.58f);
  const float x1 = std::round(width * 0.42f), x2 = std::round(width * 0.69f), xt = std::round(width * 0.58f);
  panel(audit_, panel_title(View::plan), 0, bar_h, x1, upper, body(View::plan));
  panel(audit_, panel_title(View::histogram), x1, bar_h, x2 - x1, upper, body(View::histogram));
  panel(audit_, panel_title(View::parameters), x2, bar_h, width - x2, upper, body(View::parameters));
  panel(audit_, panel_title(View::table), 0, bar_h + upper, xt, height - bar_h - upper, body(View::table));
  panel(audit_, panel_title(View::comparison), xt, bar_h + upper, width - xt, height - bar_h - upper, body(View::comparison));
}

void WorkbenchUi::draw_bar() {
  const auto& control = model_.control();
  const auto& o = model_.options();
  const ImGuiStyle& style = ImGui::GetStyle();
  const float font = ImGui::GetFontSize();
  std::string title = control.source_name + " — " + std::to_string(control.points.size()) + " points";
  if (control.source_frame || control.target_frame) {
    title += ", " + (control.source_frame ? control.source_frame->to_string() : std::string("?")) + " → " +
             (control.target_frame ? control.target_frame->to_string() : std::string("?"));
  }
  ImGui::PushFont(ImGui::GetIO().Fonts->Fonts[1]);
  detail::wrapped(audit_, title, "bar: title");
  ImGui::PopFont();

  // The controls flow: each goes on the line if it fits, else on the next.
  bool first = true;
  const float right = ImGui::GetWindowPos().x + ImGui::GetWindowContentRegionMax().x;
  const auto flow = [&](float width_px, float gap_px) {
    if (!first && ImGui::GetItemRectMax().x + gap_px + width_px <= right) ImGui::SameLine(0, gap_px);
    first = false;
  };
  const float gap = font * 1.5f;
  const auto label_w = [&](const char* s) { return ImGui::CalcTextSize(s).x; };
  const float radio_w = ImGui::GetFrameHeight() + style.ItemInnerSpacing.x;

  const float combo_w = font * 11.0f;
  flow(combo_w + style.ItemInnerSpacing.x + label_w("model"), gap);
  ImGui::SetNextItemWidth(combo_w);
  const std::string current(solver::to_string(o.model));
  if (ImGui::BeginCombo("model", current.c_str())) {
    for (auto m : {solver::FitModel::translation3, solver::FitModel::helmert6, solver::FitModel::helmert7,
                   solver::FitModel::helmert14, solver::FitModel::molodensky_badekas, solver::FitModel::enu_origin,
                   solver::FitModel::site_calibration}) {
      const bool needs_origin = m == solver::FitModel::enu_origin || m == solver::FitModel::site_calibration;
      const std::string name(solver::to_string(m));
      const int flags = needs_origin && !o.nominal_origin ? ImGuiSelectableFlags_Disabled : 0;
      if (ImGui::Selectable(name.c_str(), m == o.model, flags) && m != o.model) model_.set_model(m);
    }
    ImGui::EndCombo();
  }
  detail::check_item(audit_, "model " + current, "bar: model");
  const float convention_w = label_w("convention") + style.ItemSpacing.x + 2.0f * radio_w + label_w("position vector") +
                             style.ItemSpacing.x + label_w("coordinate frame");
  flow(convention_w, gap);
  detail::text(audit_, "convention", "bar: convention");
  ImGui::SameLine();
  const bool pv = o.convention == solver::Convention::position_vector;
  if (ImGui::RadioButton("position vector", o.convention && pv) && !(o.convention && pv)) {
    model_.set_convention(solver::Convention::position_vector);
  }
  detail::check_item(audit_, "position vector", "bar: convention");
  ImGui::SameLine();
  if (ImGui::RadioButton("coordinate frame", o.convention && !pv) && !(o.convention && !pv)) {
    model_.set_convention(solver::Convention::coordinate_frame);
  }
  detail::check_item(audit_, "coordinate frame", "bar: convention");
  flow(label_w("Save transform…") + 2.0f * style.FramePadding.x, gap);
  if (ImGui::Button("Save transform…")) ImGui::OpenPopup("Save transform");
  detail::check_item(audit_, "Save transform…", "bar: save");
  draw_save_popup();
  if (model_.busy()) {
    flow(label_w("refitting…"), gap);
    detail::text(audit_, "refitting…", "bar: status");
  } else if (!model_.fit()) {
    flow(label_w("fit refused"), gap);
    detail::text_coloured(audit_, palette::kOutlier, "fit refused", "bar: status");
  } else {
    const auto& f = *model_.fit();
    const auto& g = f.global_test;
    const std::string s = "σ0 = " + (f.sigma0 ? detail::fmt("%.3f", *f.sigma0) : std::string("undefined")) + ", dof " + std::to_string(f.dof) + (g.applicable ? "" : ", global test n/a");
    const std::string verdict = g.passed ? "global test passed" : "global test FAILED";
    flow(label_w(s.c_str()) + (g.applicable ? style.ItemSpacing.x + label_w(verdict.c_str()) : 0.0f), gap);
    detail::text(audit_, s, "bar: status");
    if (g.applicable) {
      ImGui::SameLine();
      detail::text_coloured(audit_, g.passed ? palette::kPass : palette::kOutlier, verdict, "bar: status");
    }
    const std::size_t warnings = shown_warnings(f).size();
    if (warnings > 0) {
      const std::string w = std::to_string(warnings) + (warnings == 1 ? " warning" : " warnings");
      flow(label_w(w.c_str()), gap);
      detail::text_coloured(audit_, palette::kOutlier, w, "bar: warnings");
      if (ImGui::IsItemHovered()) {
        ImGui::BeginTooltip();
        ImGui::PushTextWrapPos(font * 40.0f);
        for (const auto& line : shown_warnings(f)) ImGui::TextUnformatted(line.c_str());
        ImGui::PopTextWrapPos();
        ImGui::EndTooltip();
      }
    }
  }
  if (!status_.empty()) {
    flow(label_w(status_.c_str()), gap);
    detail::wrapped(audit_, status_, "bar: saved");
  }
}

void WorkbenchUi::draw_save_popup() {
  if (!ImGui::BeginPopupModal("Save transform", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) return;
  ImGui::TextUnformatted("The transform file, as `geoanchor fit -o` writes it:");
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 30.0f);
  ImGui::InputText("path", save_path_.data(), save_path_.size());
  ImGui::Checkbox("overwrite an existing file", &save_overwrite_);
  if (ImGui::Button("Save")) {
    try {
      model_.save_transform(save_path_.data(), save_overwrite_, options_.generator);
      status_ = std::string("wrote ") + save_path_.data();
    } catch (const Error& e) {
      status_ = e.what();
    }
    ImGui::CloseCurrentPopup();
  }
  ImGui::SameLine();
  if (ImGui::Button("Cancel")) ImGui::CloseCurrentPopup();
  ImGui::EndPopup();
}

}  // namespace geoanchor::gui
