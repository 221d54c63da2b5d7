// The options tables of docs/scene-format.md, made from the options' descriptions (option_table.cpp).
#include <set>
#include <sstream>
#include <string_view>

#include <fmt/format.h>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "scene/option_table.h"

namespace deltagi {

namespace {

// A table stands between these two lines in the docs: "<!-- options table: render -->" ... kTableEnd.
constexpr std::string_view kTableBegin = "<!-- options table: ", kMarkerEnd = " -->";
constexpr std::string_view kTableEnd = "<!-- end of options table -->";

// The default's JSON, as the scene file would give it: floats with the digits a float has ("0.98").
std::string defaultText(const OptionInfo& option) {
    const nlohmann::json value = option.write(Options{});
    std::string text = value.is_number_float() ? fmt::format("`{:.6g}`", value.get<double>())
                                               : fmt::format("`{}`", value.dump());
    return option.defaultNote.empty() ? text : text + ": " + option.defaultNote;
}

std::string tableOf(const OptionGroup& group) {
    std::string table = "| key | type | unit | default | meaning |\n|---|---|---|---|---|\n";
    for (const OptionInfo& option : group.options)
        table += fmt::format("| `{}` | {} | {} | {} | {} |\n", option.key, option.type,
                             option.unit.empty() ? "—" : option.unit, defaultText(option), option.doc);
    return table;
}

const OptionGroup* findGroup(std::string_view name) {
    for (const OptionGroup& group : optionTable())
        if (group.name == name) return &group;
    return nullptr;
}

}  // namespace

std::string optionTablesMarkdown() {
    std::string markdown;
    for (const OptionGroup& group : optionTable())
        markdown +=
            fmt::format("{}{}{}\n{}{}\n\n", kTableBegin, group.name, kMarkerEnd, tableOf(group), kTableEnd);
    return markdown;
}

std::string withOptionTables(const std::string& markdown, const std::string& file) {
    std::istringstream in(markdown);
    std::string result, line;
    std::set<std::string_view> made;
    const OptionGroup* open = nullptr;  // the group whose table is being replaced
    int lineNumber = 0, openLine = 0;
    auto fail = [&file](int at, const std::string& what) {
        throw InputError(fmt::format("{}: line {}", file, at), what);
    };
    while (std::getline(in, line)) {
        ++lineNumber;
        if (open) {
            if (line != kTableEnd) continue;
            result += line + "\n";
            open = nullptr;
        } else if (line.starts_with(kTableBegin) && line.ends_with(kMarkerEnd)) {
            const std::string name =
                line.substr(kTableBegin.size(), line.size() - kTableBegin.size() - kMarkerEnd.size());
            open = findGroup(name);
            if (!open)
                fail(lineNumber, fmt::format("no options group '{}' (src/scene/option_table.cpp)", name));
            if (!made.insert(open->name).second) fail(lineNumber, "a second table of options." + name);
            openLine = lineNumber;
            result += line + "\n" + tableOf(*open);
        } else {
            result += line + "\n";
        }
    }
    if (open)
        fail(openLine, fmt::format("the table of options.{} has no '{}' after it", open->name, kTableEnd));
    for (const OptionGroup& group : optionTable())
        if (!made.contains(group.name))
            throw InputError(file, fmt::format("no table of options.{} ('{}{}{}')", group.name, kTableBegin,
                                               group.name, kMarkerEnd));
    if (!markdown.ends_with('\n') && !result.empty()) result.pop_back();
    return result;
}

}  // namespace deltagi
