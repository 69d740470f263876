// SPDX-License-Identifier: MIT
#include "uvr/facade/series_player.h"

#include <chrono>
#include <optional>
#include <utility>

#include "uvr/core/error.h"
#include "uvr/cpu/background_task.h"
#include "uvr/dist/communicator.h"
#include "uvr/dist/decompose.h"

namespace uvr {

namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

/// One step's read: its fields when the geometry is the current one, else its whole mesh.
struct SeriesPlayer::Read {
    std::optional<std::vector<Field>> fields;
    std::optional<Mesh> mesh;
    std::optional<MeshPart> part;  ///< byParts: this rank's parts of another geometry
    double seconds = 0.0;
};

/// A read started by prefetch.
struct SeriesPlayer::Pending {
    std::size_t step = 0;
    cpu::BackgroundTask<Read> task;
};

SeriesPlayer::SeriesPlayer(std::unique_ptr<MeshSeries> series, FieldSpec spec,
                           const RendererOptions& options, std::size_t first,
                           const ProgressFn& progress)
    : series_(std::move(series)), spec_(std::move(spec)), options_(options), progress_(progress) {
    UVR_CHECK(series_ != nullptr, "a player needs a series");
    // Data-parallel, every rank reads the steps: a rank that fails ends every rank.
    if (const Communicator* comm = options_.communicator; comm && comm->size() > 1) {
        std::uint64_t parts = 0;
        agreed([&] { parts = series_->partCount(first); });
        if (parts >= std::uint64_t(comm->size())) parts_ = rankRunOfStep(*series_, first, *comm);
    }
    if (parts_) {
        agreed([&] { part_ = series_->readPart(first, parts_->first, parts_->second); });
        renderer_ = partRenderer(part_);
        step_ = first;
        return;
    }
    agreed([&] {
        mesh_ = series_->readStep(first);
        field_ = selectScalarField(mesh_, spec_);  // the choice as the first step explains it
    });
    const std::string choice = field_.choice;
    spec_ = pinField(mesh_, spec_);  // every step the field this one chose
    field_.choice = choice;
    renderer_ = std::make_unique<Renderer>(mesh_, field_, options_, progress_);
    step_ = first;
}

std::unique_ptr<Renderer> SeriesPlayer::partRenderer(const MeshPart& part) {
    // The part is kept (its fields give the next steps' values); a copy becomes the share.
    MeshShare share = shareOfPart(*options_.communicator, MeshPart(part), spec_);
    spec_.name = share.field.name;  // every step the field the ranks chose at this one
    spec_.association = share.field.association;
    ScalarField field = share.field;
    auto renderer = std::make_unique<Renderer>(std::move(share), options_, progress_);
    field_ = std::move(field);
    return renderer;
}

SeriesPlayer::~SeriesPlayer() = default;

template <class F>
void SeriesPlayer::agreed(F&& work) {
    if (options_.communicator)
        agreeOn(*options_.communicator, std::forward<F>(work));
    else
        work();
}

SeriesPlayer::Read SeriesPlayer::readStep(std::size_t i) {
    const auto start = std::chrono::steady_clock::now();
    Read r;
    if (parts_) {
        const auto [first, end] = rankRunOfStep(*series_, i, *options_.communicator);
        MeshPart part = series_->readPart(i, first, end);
        if (samePartGeometry(part, part_.mesh, part_.pointIds, part_.cellIds))
            r.fields = std::move(part.mesh.fields);
        else
            r.part = std::move(part);
    } else {
        r.fields = series_->readFieldsIfSameGeometry(i, mesh_);
        if (!r.fields) r.mesh = series_->readStep(i);
    }
    r.seconds = secondsSince(start);
    return r;
}

std::vector<float> SeriesPlayer::stepValues(std::size_t i) {
    pending_.reset();  // one reader at a time: a prefetch is waited for and dropped
    std::vector<float> values;
    agreed([&] {
        Read r = readStep(i);
        const Mesh& geometry = r.fields ? current() : r.part ? r.part->mesh : *r.mesh;
        const std::vector<Field>& fields = r.fields ? *r.fields : geometry.fields;
        std::vector<FieldInfo> infos;
        for (const Field& f : fields) infos.push_back({f.name, f.association, f.components});
        const FieldChoice choice = resolveField(infos, spec_);
        values = scalarFieldOf(geometry, fields[choice.index], spec_.component).values;
    });
    return values;
}

void SeriesPlayer::prefetch(std::size_t i) {
    if (i >= series_->stepCount() || i == step_) return;
    if (pending_ && pending_->step == i) return;
    pending_.reset();  // waits for an earlier read: one reader at a time
    auto p = std::make_unique<Pending>();
    p->step = i;
    p->task = cpu::BackgroundTask<Read>([this, i] { return readStep(i); });
    pending_ = std::move(p);
}

StepUpdate SeriesPlayer::show(std::size_t i, std::optional<std::size_t> next) {
    StepUpdate u;
    u.step = i;
    u.time = series_->times().at(std::min(i, series_->stepCount() - 1));
    // Step 1: the step's data, from the prefetch when it read this step.
    const auto waitStart = std::chrono::steady_clock::now();
    std::unique_ptr<Pending> pending = std::move(pending_);
    Read r;
    agreed([&] {
        if (pending && pending->step == i) {
            r = pending->task.take();
            u.prefetched = true;
            u.readSeconds = secondsSince(waitStart);
        } else {
            pending.reset();  // a read of another step is waited for and dropped
            r = readStep(i);
            u.readSeconds = r.seconds;
        }
    });
    if (Communicator* comm = options_.communicator) {
        // Every rank takes the same path below (each read the same files).
        std::uint64_t same[2] = {r.fields ? 1u : 0u, r.fields ? 0u : 1u};
        comm->allReduce(same, ReduceOp::Max);
        if (same[0] && same[1])
            throwError(ErrorKind::Io, series_->stepSource(i),
                       "the ranks read time step " + std::to_string(i) +
                           " differently (the same geometry on some, another on others)");
    }
    // Step 2: new values for the same geometry, or the new geometry prepared.
    const auto updateStart = std::chrono::steady_clock::now();
    if (r.fields) {
        // The geometry stays: the next read (it only reads the points and cells) can start now.
        if (next) prefetch(*next);
        std::vector<Field> previous = std::exchange(current().fields, std::move(*r.fields));
        try {
            ScalarField field;
            agreed([&] { field = selectScalarField(current(), spec_); });
            renderer_->setFieldValues(field);
            field_ = std::move(field);
        } catch (...) {
            current().fields = std::move(previous);
            throw;
        }
    } else if (r.part) {
        agreed([&] { selectScalarField(r.part->mesh, spec_); });  // the field is there
        auto renderer = partRenderer(*r.part);
        part_ = std::move(*r.part);
        renderer_ = std::move(renderer);
        u.rebuilt = true;
    } else {
        ScalarField field;
        agreed([&] { field = selectScalarField(*r.mesh, spec_); });
        auto renderer = std::make_unique<Renderer>(*r.mesh, field, options_, progress_);
        mesh_ = std::move(*r.mesh);
        field_ = std::move(field);
        renderer_ = std::move(renderer);
        u.rebuilt = true;
    }
    u.updateSeconds = secondsSince(updateStart);
    step_ = i;
    if (next) prefetch(*next);  // after a new geometry (nothing when already reading it)
    return u;
}

}  // namespace uvr
