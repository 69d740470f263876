// SPDX-License-Identifier: MIT
#include "parse_errors.h"

#include "uvr/core/text.h"

#include <algorithm>
#include <map>

namespace uvr::cli {

std::string closest(const std::string& word, const std::vector<std::string>& candidates) {
    const int limit = std::max(2, static_cast<int>(word.size()) / 3);
    std::string best;
    int bestDistance = limit + 1;
    for (const std::string& c : candidates) {
        const int d = uvr::editDistance(word, c);
        if (d < bestDistance) best = c, bestDistance = d;
    }
    return best;
}

namespace {

/// Names ParaView and other tools use for uvr's options.
const std::map<std::string, std::string>& aliases() {
    static const std::map<std::string, std::string> names = {
        {"--colormap", "--tf"},
        {"--color-map", "--tf"},
        {"--cmap", "--tf"},
        {"--colormap-preset", "--tf"},
        {"--preset", "--tf"},
        {"--lut", "--tf"},
        {"--transfer-function", "--tf"},
        {"--output", "-o"},
        {"--out", "-o"},
        {"--scalars", "--field"},
        {"--array", "--field"},
        {"--resolution", "--size"},
        {"--image-size", "--size"},
        {"--camera-file", "--camera"},
        // The sample spacing was --step until issue 35: a time step is --step-index.
        {"--step",
         "--sample-distance for the sample spacing, or --step-index or --time for a "
         "time step"},
        {"--max-step", "--max-sample-distance"},
        {"--sampledistance", "--sample-distance"},
        {"--unit-distance", "--opacity-unit"},
        {"--log-scale", "--log"},
        {"--use-log-scale", "--log"},
        {"--logscale", "--log"},
        {"--nan-colour", "--nan-color"},
        {"--nancolor", "--nan-color"},
    };
    return names;
}

/// Every long and short option name of app ("--tf", "-o").
std::vector<std::string> optionNames(const CLI::App& app) {
    std::vector<std::string> out;
    for (const CLI::Option* o : app.get_options()) {
        for (const std::string& n : o->get_lnames()) out.push_back("--" + n);
        for (const std::string& n : o->get_snames()) out.push_back("-" + n);
    }
    return out;
}

}  // namespace

std::string describeParseError(CLI::App& app, const std::vector<std::string>& args,
                               const CLI::ParseError& error) {
    // The subcommand in use: the first argument naming one.
    CLI::App* sub = nullptr;
    std::vector<std::string> commands;
    for (CLI::App* s : app.get_subcommands([](CLI::App*) { return true; }))
        commands.push_back(s->get_name());
    for (const std::string& a : args)
        if (std::find(commands.begin(), commands.end(), a) != commands.end()) {
            sub = app.get_subcommand(a);
            break;
        }
    const std::string help = sub ? "uvr " + sub->get_name() + " --help" : "uvr --help";
    if (!sub) {
        // No subcommand: the first word that is not an option is a misspelt one.
        for (const std::string& a : args) {
            if (a.empty() || a[0] == '-') continue;
            const std::string guess = closest(a, commands);
            return "unknown command '" + a + "'" +
                   (guess.empty() ? "" : ": did you mean '" + guess + "'?") + " (see " + help + ")";
        }
    }
    // Unknown options: every argument that looks like one and names no option here.
    std::vector<std::string> known = optionNames(app);
    if (sub) {
        const std::vector<std::string> own = optionNames(*sub);
        known.insert(known.end(), own.begin(), own.end());
    }
    std::string unknown;
    for (const std::string& a : args) {
        if (a.size() < 2 || a[0] != '-' || a == "--") continue;
        if (a[1] != '-' && std::isdigit(static_cast<unsigned char>(a[1]))) continue;  // -1.5
        const std::string name = a.substr(0, a.find('='));
        if (std::find(known.begin(), known.end(), name) != known.end()) continue;
        const auto alias = aliases().find(name);
        std::string guess = alias != aliases().end() ? alias->second : closest(name, known);
        if (!unknown.empty()) unknown += "; ";
        unknown +=
            "unknown option " + name + (guess.empty() ? "" : " (did you mean " + guess + "?)");
    }
    if (!unknown.empty()) return unknown + " (see " + help + ")";
    return std::string(error.what()) + " (see " + help + ")";
}

}  // namespace uvr::cli
