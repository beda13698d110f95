#pragma once
// The HTML page being written: escaped text, tables and inline figures (report/src/html.cpp).

#include <string>
#include <vector>

#include "furuta/report/balance_page.hpp"
#include "furuta/report/report.hpp"

namespace furuta::report {

// The pages' one style sheet (report.html of identify and of `furuta report`).
inline constexpr const char* kPageStyle = R"(
body { font-family: sans-serif; max-width: 1200px; margin: 2em auto; padding: 0 1em; color: #222;
       line-height: 1.4; }
h1 { margin-bottom: 0.2em; }
h2 { border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 2em; }
.meta { color: #666; }
nav ol { columns: 2; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.9em; }
caption { caption-side: top; text-align: left; font-weight: bold; padding-bottom: 0.3em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.5em; text-align: right; }
.table { overflow-x: auto; }
thead th { background: #f0f0f0; }
tbody th { text-align: left; font-weight: normal; overflow-wrap: break-word; }
code { overflow-wrap: anywhere; }
#sessions tbody th { overflow-wrap: anywhere; min-width: 12em; }
.keys { font-size: 0.9em; margin-top: -0.5em; }
.keys li { overflow-wrap: anywhere; }
figure { margin: 1em 0; }
figure svg { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #444; }
.warnings li { margin: 0.2em 0; }
.warnings li.failed, .warnings li.suspect { border-left: 3px solid #b00020; padding-left: 0.4em; }
.topic { display: inline-block; min-width: 6em; font-weight: bold; color: #8a4b00; }
.absent { color: #666; font-style: italic; }
.none { color: #2a6e2a; }
.physical { border: 3px solid #b00020; background: #fff0f0; padding: 0.2em 1em; margin: 1em 0; }
.physical h2 { color: #b00020; border: none; margin-top: 0.5em; }
.balance-log h3 { margin-top: 1.5em; }
.certified { color: #2a6e2a; font-weight: bold; }
.not-certified { border: 3px solid #b00020; background: #fff0f0; padding: 0.2em 1em; margin: 1em 0; }
.sampled-outside { color: #b00020; font-weight: bold; }
)";

class Html {
 public:
  void raw(const std::string& text) { out_ += text; }
  void text(const std::string& text) { out_ += escape_html(text); }
  // <tag attributes>escaped text</tag>
  void element(const std::string& tag, const std::string& text,
               const std::string& attributes = "") {
    out_ += "<" + tag + (attributes.empty() ? "" : " " + attributes) + ">" + escape_html(text) +
            "</" + tag + ">";
  }
  void paragraph(const std::string& text, const std::string& css_class = "") {
    element("p", text, css_class.empty() ? "" : "class=\"" + css_class + "\"");
    out_ += "\n";
  }
  void table(const std::string& id, const std::string& caption,
             const std::vector<std::string>& header,
             const std::vector<std::vector<std::string>>& rows) {
    // Wide tables scroll on their own rather than widening the page.
    out_ += "<div class=\"table\"><table id=\"" + escape_html(id) + "\">\n";
    element("caption", caption);
    out_ += "\n<thead><tr>";
    for (const auto& h : header) element("th", h, "scope=\"col\"");
    out_ += "</tr></thead>\n<tbody>\n";
    for (const auto& row : rows) {
      out_ += "<tr>";
      for (std::size_t i = 0; i < row.size(); ++i) {
        if (i == 0) {
          element("th", row[i], "scope=\"row\"");
        } else {
          element("td", row[i]);
        }
      }
      out_ += "</tr>\n";
    }
    out_ += "</tbody>\n</table></div>\n";
  }
  // The document up to its header's first paragraph: the doctype, the head with `title` and the
  // shared style, the body's header with the title and `about` (class "meta"). The header is left
  // open for the page's own lines.
  void document_start(const std::string& title, const std::string& about) {
    raw("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    raw("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    element("title", title);
    raw("\n<style>");
    raw(kPageStyle);
    raw("</style>\n</head>\n<body>\n<header>\n");
    element("h1", title);
    paragraph(about, "meta");
  }
  void figure(const std::string& id, const std::string& svg, const std::string& caption) {
    out_ += "<figure id=\"" + escape_html(id) + "\">\n" + inline_svg(svg, id);
    element("figcaption", caption);
    out_ += "\n</figure>\n";
  }
  const std::string& str() const { return out_; }

 private:
  // An SVG document as an element of the page: an XML declaration or doctype is not allowed
  // there, and its ids (clip paths) share the page's namespace with every other figure's, so
  // they take the figure's id as a prefix.
  static std::string inline_svg(const std::string& svg, const std::string& figure) {
    const std::size_t at = svg.find("<svg");
    if (at == std::string::npos) return {};
    std::string out = svg.substr(at);
    for (const std::string marker : {" id=\"", "url(#", "href=\"#"}) {
      const std::string prefixed = marker + figure + "-";
      for (std::size_t i = out.find(marker); i != std::string::npos;
           i = out.find(marker, i + prefixed.size())) {
        out.replace(i, marker.size(), prefixed);
      }
    }
    return out;
  }
  std::string out_;
};

// The balance sessions' parts of a page (balance_page.cpp), one <section class="balance-log"> per
// log with its heading as `heading` (h2 on its own page, h3 inside the identification's): a
// balance session's figures table and figure (ids "balance-figures-<n>", "fig-balance-<n>", n
// from 1 in the logs' order), another log's profile and samples.
void balance_log_sections(Html& h, const std::vector<BalanceLogEntry>& logs,
                          const std::string& heading);

}  // namespace furuta::report
