#include "server/app/index_page.hpp"

namespace tinsmith::server {

namespace {

std::string escapeHtml(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace

std::string indexPageHtml(const std::vector<std::shared_ptr<const Tileset>>& tilesets,
                          const std::string& basePath, const std::string& notice) {
  const std::string base = escapeHtml(basePath);
  std::string html =
      "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
      "<title>tinsmith</title><style>body{font:15px system-ui,sans-serif;margin:2em;max-width:60em}"
      "table{border-collapse:collapse}td,th{padding:.3em .8em;border-bottom:1px solid #ddd;"
      "text-align:left}.notice{background:#fff4d6;border:1px solid #e0c060;padding:.6em 1em}"
      "</style></head><body>\n<h1>tinsmith</h1>\n";
  if (!notice.empty()) html += "<p class=\"notice\">" + escapeHtml(notice) + "</p>\n";
  html += "<p>";
  html += std::to_string(tilesets.size());
  html += " tileset(s). JSON: <a href=\"" + base + "/tilesets\">/tilesets</a>, <a href=\"" + base +
          "/health\">/health</a>, <a href=\"" + base + "/metrics\">/metrics</a>.</p>\n"
          "<table><tr><th>id</th><th>store</th><th>CRS</th><th>tiles</th><th>zooms</th>"
          "<th>links</th></tr>\n";
  for (const auto& t : tilesets) {
    const auto& s = t->summary();
    const std::string id = escapeHtml(t->id());
    html += "<tr><td>" + id + "</td><td>" + escapeHtml(s["name"].get<std::string>()) + "</td><td>" +
            escapeHtml(t->crs()) + "</td><td>" + s["tileCount"].dump() + "</td><td>" +
            s["zooms"]["min"].dump() + "–" + s["zooms"]["max"].dump() +
            "</td><td><a href=\"" + base + "/tilesets/" + id + "/tileset.json\">tileset.json</a></td></tr>\n";
  }
  html += "</table>\n</body></html>\n";
  return html;
}

}  // namespace tinsmith::server
