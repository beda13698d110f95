#pragma once
// The HTML page being written: escaped text, tables and inline figures (report/src/html.cpp).

#include <string>
#include <vector>

#include "furuta/report/report.hpp"

namespace furuta::report {

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

}  // namespace furuta::report
