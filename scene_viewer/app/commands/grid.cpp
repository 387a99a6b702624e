#include "grid.hpp"

#include <algorithm>
#include <filesystem>

#include "scene_viewer/figure/grid_figure.hpp"
#include "scene_viewer/render/render_setup.hpp"
#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/output_transaction.hpp"

namespace scene_render {

using namespace scene_viewer;

CLI::App* add_grid_command(CLI::App& app, GridArgs& a) {
    CLI::App* grid = app.add_subcommand("grid", "render several entity files into a labelled grid");
    grid->add_option("--inputs", a.inputs, "entity files")->required();
    grid->add_option("--labels", a.labels, "one label per input (default: file names)");
    grid->add_option("-o,--output", a.output, "output PNG, '-' for stdout")->required();
    grid->add_option("--columns", a.columns, "tiles per row (default: square-ish)");
    add_view_options(*grid, a.view);
    return grid;
}

int run_grid(GridArgs a) {
    if (a.columns < 0 || a.columns > static_cast<int>(std::max<std::size_t>(a.inputs.size(), 1))) {
        usage("must be 0 (square-ish) to the number of inputs", "--columns");
    }
    if (a.output != "-") {
        try {
            stereoscene::support::check_output_path(a.output);
        } catch (const stereoscene::support::FileError& e) {
            throw Failure{"unusable output path", e.reason(), a.output};
        }
    }
    if (!a.labels.empty() && a.labels.size() != a.inputs.size()) {
        usage(std::to_string(a.labels.size()) + " labels for " + std::to_string(a.inputs.size()) +
                  " inputs",
              "--labels");
    }
    std::vector<scene_schema::EntityDocument> documents;
    for (const auto& path : a.inputs) documents.push_back(read_entities(path));
    RenderOptions options = render_options(a.view, documents.front(), a.inputs.front());
    share_view(documents, options);
    const auto cloud = read_cloud(a.view);
    const auto classes = read_classes(a.view.boxes, a.view.classes);
    if (a.labels.empty()) {
        for (const auto& path : a.inputs) {
            a.labels.push_back(std::filesystem::path(path).stem().string());
        }
    }
    auto gpu = start_gpu(classes);
    std::vector<ImageRgba8> tiles;
    for (const auto& document : documents) {
        gpu->renderer.load(document, cloud ? &*cloud : nullptr, options);
        if (classes) warn_boxes(gpu->renderer, *classes);
        tiles.push_back(gpu->renderer.render_frame());
    }
    GridFigureOptions figure;
    figure.columns = a.columns;
    write_png_output(a.output, compose_grid(tiles, a.labels, figure));
    return 0;
}

}  // namespace scene_render
