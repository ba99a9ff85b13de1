// Durability benchmarks (a plain program; never run by CTest; results in NOTES.md):
//
//   edits   8 HTTP clients (keep-alive httplib clients, one thread each) post small batches (one
//           set_transform) to an in-process strata-server for a few seconds, with a data
//           directory in each --fsync mode and without one; batches/s, fsyncs, batches/fsync.
//   restart a scene is written through a DurableStore, then reopened: time to recover (load and
//           replay) and to build its acceleration structures; from the journal alone and from a
//           snapshot. Scenes: 1M instances of one small mesh, and 10 meshes of 1M triangles.
//
//   stall   a 1M-instance scene behind a DurableStore; one thread applies one-edit batches
//           (set_transform of a random instance) back to back while snapshots are written; the
//           longest apply() that overlapped a snapshot, against the longest one in windows of
//           the same length without a snapshot (the baseline, same run).
//
//   replace a 1M-instance scene behind a DurableStore is replaced by another 1M-instance scene's
//           snapshot (DurableStore::replace_scene, what a replica does over a trimmed gap) while
//           one thread reads the scene version back to back: the scene lock's hold during the
//           swap, the longest read during the replace against the longest in as long a window
//           without one, and as the baseline restore_snapshot of the same bytes into an empty
//           engine (how long loading under the lock would hold it).
//
//   image   a 1M-instance scene's snapshot as SceneImage::to_batch writes it (runs of instances
//           packed into bulk adds, numbered ids as ranges) against the same scene written one
//           add_instance per instance (the baseline, what snapshots held before): bytes, encode
//           time, and restore_snapshot into an empty engine, alternating, same run.
//
//   build/tests/bench/strata_durable_bench [edits|restart|stall|replace|image|all] [runs]
//   (default: all 3)
//   STRATA_BENCH_DIR picks where the data directories go (default: $TMPDIR).

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <httplib.h>
#include <spdlog/spdlog.h>

#include "engine/core/timer.h"
#include "engine/durable/durable_store.h"
#include "engine/durable/journal_format.h"
#include "engine/engine.h"
#include "engine/scene/shapes.h"
#include "server/server.h"
#include "tests/engine/bulk_singles.h"

namespace strata {
namespace {

std::string temp_dir() {
    const char* base = std::getenv("STRATA_BENCH_DIR");
    std::string pattern =
        std::string(base ? base : std::filesystem::temp_directory_path().c_str()) +
        "/strata-bench-XXXXXX";
    if (!::mkdtemp(pattern.data())) std::abort();
    return pattern;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

std::unique_ptr<Engine> engine() {
    EngineConfig c;
    c.budget = {uint64_t(1) << 26, uint64_t(1) << 26};
    auto e = Engine::create(c);
    if (!e) std::abort();
    return std::move(e.value());
}

// Step: edits per second ----------------------------------------------------------------------

struct EditsResult {
    double batches_per_s = 0;
    uint64_t fsyncs = 0;
    uint64_t batches = 0;
    uint64_t max_group = 0;
};

EditsResult run_edits(const char* mode, double seconds, int clients) {
    auto eng = engine();
    std::string dir;
    std::unique_ptr<durable::DurableStore> store;
    if (std::string(mode) != "memory") {
        dir = temp_dir();
        durable::StoreOptions o;
        o.dir = dir;
        o.journal.mode = std::string(mode) == "always"  ? durable::FsyncMode::Always
                         : std::string(mode) == "batch" ? durable::FsyncMode::Batch
                                                        : durable::FsyncMode::Off;
        auto s = durable::DurableStore::open(o, *eng);
        if (!s) {
            std::fprintf(stderr, "%s\n", s.error().message.c_str());
            std::abort();
        }
        store = std::move(s.value());
    }
    EditBatch setup;
    setup.edits.emplace_back(add_mesh_edit("box", make_box(Vec3(0.5f))));
    for (int c = 0; c < clients; ++c) {
        AddInstance i;
        i.id = "i" + std::to_string(c);
        i.mesh = "box";
        setup.edits.emplace_back(i);
    }
    if (!eng->apply(std::move(setup))) std::abort();

    server::ServerConfig config;
    config.port = 0;
    config.threads = std::size_t(clients);
    server::Server http(config, *eng, store.get());
    auto port = http.bind();
    if (!port) std::abort();
    std::thread serving([&] { http.listen(); });

    std::atomic<bool> stop{false};
    std::atomic<uint64_t> done{0};
    const durable::DurableStats before = store ? store->stats() : durable::DurableStats{};
    std::vector<std::thread> threads;
    Stopwatch clock;
    for (int c = 0; c < clients; ++c) {
        threads.emplace_back([&, c] {
            httplib::Client client("127.0.0.1", port.value());
            client.set_keep_alive(true);
            client.set_tcp_nodelay(true);  // else Nagle and delayed ACKs cap each client at ~25/s
            uint64_t n = 0;
            while (!stop.load()) {
                const std::string body = R"({"edits":[{"op":"set_transform","instance":"i)" +
                                         std::to_string(c) + R"(","transform":{"translate":[)" +
                                         std::to_string(n++ % 100) + ",0,0]}}]}";
                auto r = client.Post("/v1/edits", body, "application/json");
                if (!r || r->status != 200) std::abort();
                done.fetch_add(1);
            }
        });
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    stop = true;
    for (auto& t : threads) t.join();
    const double elapsed = clock.ms() / 1000.0;
    EditsResult out;
    out.batches = done.load();
    out.batches_per_s = double(out.batches) / elapsed;
    if (store) {
        const durable::DurableStats after = store->stats();
        out.fsyncs = after.fsyncs - before.fsyncs;
        out.max_group = after.batches_per_fsync_max;
    }
    http.stop();
    serving.join();
    store.reset();
    if (!dir.empty()) std::filesystem::remove_all(dir);
    return out;
}

void bench_edits(int runs) {
    constexpr int CLIENTS = 8;
    std::printf("edits: %d clients, one set_transform per batch, 3 s per run, %d runs, median\n",
                CLIENTS, runs);
    const char* modes[] = {"always", "batch", "off", "memory"};
    std::vector<std::vector<EditsResult>> results(4);
    // Interleaved, so that the modes see the same machine load.
    for (int r = 0; r < runs; ++r)
        for (int m = 0; m < 4; ++m) results[m].push_back(run_edits(modes[m], 3.0, CLIENTS));
    for (int m = 0; m < 4; ++m) {
        std::vector<double> rate, per_fsync;
        uint64_t max_group = 0;
        for (const auto& e : results[m]) {
            rate.push_back(e.batches_per_s);
            if (e.fsyncs) per_fsync.push_back(double(e.batches) / double(e.fsyncs));
            max_group = std::max(max_group, e.max_group);
        }
        std::printf("  %-7s %8.0f batches/s", modes[m], median(rate));
        if (!per_fsync.empty())
            std::printf("   %.2f batches per fsync (largest group %llu)", median(per_fsync),
                        static_cast<unsigned long long>(max_group));
        std::printf("\n");
    }
    // Without company a batch pays a whole fsync: what group commit saves.
    std::vector<double> single;
    for (int r = 0; r < runs; ++r) single.push_back(run_edits("always", 3.0, 1).batches_per_s);
    std::printf("  always, 1 client: %.0f batches/s (one fsync each)\n", median(single));
}

// Step: restart time --------------------------------------------------------------------------

struct RestartResult {
    double recover_s = 0;
    double build_s = 0;
    uint64_t disk_bytes = 0;
};

/// Writes `batches` through a store in `dir` (snapshot at the end when asked), closes it.
/// A store on `dir` journaling with `mode` that takes no snapshot of its own (the benches say
/// when).
std::unique_ptr<durable::DurableStore> store_without_snapshots(Engine& eng, const std::string& dir,
                                                               durable::FsyncMode mode) {
    durable::StoreOptions o;
    o.dir = dir;
    o.journal.mode = mode;
    o.snapshot_threshold_bytes = UINT64_MAX;
    auto opened = durable::DurableStore::open(o, eng);
    if (!opened) std::abort();
    return std::move(opened.value());
}

/// One timed call on one clock (the stall and replace benches keep those over a threshold).
using Clock = std::chrono::steady_clock;
struct Span {
    Clock::time_point begin, end;
};

void write_scene(const std::string& dir, std::vector<EditBatch> batches, bool snapshot) {
    auto eng = engine();
    // The write side is not what is measured.
    auto store = store_without_snapshots(*eng, dir, durable::FsyncMode::Off);
    for (auto& b : batches)
        if (!eng->apply(std::move(b))) std::abort();
    if (!snapshot) return;
    if (!store->snapshot_now()) std::abort();
    const durable::DurableStats st = store->stats();
    std::printf(
        "    snapshot at version %llu: %.1f ms holding the scene lock (the copy), %.2f s in "
        "all, %.0f MB\n",
        static_cast<unsigned long long>(st.last_snapshot_version), st.last_snapshot_lock_ms,
        st.last_snapshot_seconds, double(st.last_snapshot_bytes) / 1e6);
}

RestartResult restart(const std::string& dir) {
    auto eng = engine();
    durable::StoreOptions o;
    o.dir = dir;
    RestartResult out;
    Stopwatch clock;
    auto store = durable::DurableStore::open(o, *eng);
    if (!store) std::abort();
    out.recover_s = clock.ms() / 1000.0;
    Stopwatch build;
    if (!eng->commit()) std::abort();
    out.build_s = build.ms() / 1000.0;
    for (const auto& e : std::filesystem::directory_iterator(dir))
        if (e.is_regular_file()) out.disk_bytes += e.file_size();
    return out;
}

std::vector<EditBatch> million_instances() {
    std::vector<EditBatch> batches(1);
    batches[0].edits.emplace_back(add_mesh_edit("pebble", make_sphere(0.4f, 8)));
    constexpr int N = 1000000, PER_BATCH = 10000;
    for (int i = 0; i < N; ++i) {
        if (i % PER_BATCH == 0) batches.emplace_back();
        AddInstance e;
        e.id = "instance-" + std::to_string(i);
        e.mesh = "pebble";
        e.transform = Affine::translation({float(i % 1000), 0.0f, float(i / 1000)});
        batches.back().edits.emplace_back(std::move(e));
    }
    return batches;
}

std::vector<EditBatch> ten_million_triangles() {
    std::vector<EditBatch> batches;
    for (int m = 0; m < 10; ++m) {
        EditBatch b;
        b.edits.emplace_back(add_mesh_edit("mesh-" + std::to_string(m), make_sphere(1.0f, 1000)));
        AddInstance e;
        e.id = "instance-" + std::to_string(m);
        e.mesh = "mesh-" + std::to_string(m);
        e.transform = Affine::translation({float(m) * 2.5f, 0.0f, 0.0f});
        b.edits.emplace_back(std::move(e));
        batches.push_back(std::move(b));
    }
    return batches;
}

void bench_restart(int runs) {
    std::printf("restart: recover (lock, load, replay) and build, %d runs each, median\n", runs);
    struct Case {
        const char* name;
        std::vector<EditBatch> (*make)();
    } cases[] = {{"1M instances", million_instances}, {"10M triangles", ten_million_triangles}};
    for (const Case& c : cases) {
        for (bool snapshot : {false, true}) {
            const std::string dir = temp_dir();
            write_scene(dir, c.make(), snapshot);
            std::vector<double> recover, build;
            uint64_t bytes = 0;
            for (int r = 0; r < runs; ++r) {
                const RestartResult res = restart(dir);
                recover.push_back(res.recover_s);
                build.push_back(res.build_s);
                bytes = res.disk_bytes;
            }
            std::printf("  %-14s from %-8s %7.2f s recover + %6.2f s build   (%.0f MB on disk)\n",
                        c.name, snapshot ? "snapshot" : "journal", median(recover), median(build),
                        double(bytes) / 1e6);
            std::filesystem::remove_all(dir);
        }
    }
}

// Step: edit stalls during a snapshot ---------------------------------------------------------

struct StallResult {
    double with_snapshot_ms = 0;  ///< the longest apply() overlapping a snapshot
    double without_ms = 0;        ///< the longest apply() in as long a window without one
    double lock_ms = 0;           ///< the snapshot's own measure of its critical section
    double snapshot_s = 0;        ///< the whole snapshot, serialisation and fsync included
};

StallResult run_stall() {
    auto eng = engine();
    const std::string dir = temp_dir();
    // The stall, not the fsync, is measured.
    auto store = store_without_snapshots(*eng, dir, durable::FsyncMode::Off);
    for (auto& b : million_instances())
        if (!eng->apply(std::move(b))) std::abort();
    if (!eng->commit()) std::abort();

    // One editor: each apply() is timed from its start to its return, on one clock.
    std::vector<Span> spans;
    spans.reserve(1 << 22);
    std::atomic<bool> stop{false};
    std::thread editor([&] {
        uint64_t n = 0;
        while (!stop.load(std::memory_order_relaxed)) {
            EditBatch b;
            SetTransform e;
            e.instance = "instance-" + std::to_string((n * 7919) % 1000000);
            e.transform = Affine::translation({float(n % 100), 1.0f, 0.0f});
            b.edits.emplace_back(std::move(e));
            const auto t0 = Clock::now();
            if (!eng->apply(std::move(b))) std::abort();
            spans.push_back({t0, Clock::now()});
            ++n;
        }
    });
    auto longest = [&](Clock::time_point a, Clock::time_point b, std::size_t upto) {
        double worst = 0;
        for (std::size_t i = 0; i < upto; ++i)
            if (spans[i].end >= a && spans[i].begin <= b)
                worst = std::max(worst, std::chrono::duration<double, std::milli>(
                                            spans[i].end - spans[i].begin)
                                            .count());
        return worst;
    };
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    // The baseline window first, then the snapshot, each as long as the snapshot takes.
    const auto quiet_begin = Clock::now();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const auto snap_begin = Clock::now();
    if (!store->snapshot_now()) std::abort();
    const auto snap_end = Clock::now();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    std::this_thread::sleep_for(snap_end - snap_begin);
    const auto quiet2_begin = Clock::now();
    std::this_thread::sleep_for(snap_end - snap_begin);
    const auto quiet2_end = Clock::now();
    stop = true;
    editor.join();
    const std::size_t n = spans.size();
    StallResult out;
    out.with_snapshot_ms = longest(snap_begin, snap_end, n);
    out.without_ms = std::max(longest(quiet_begin, snap_begin, n),
                              longest(quiet2_begin, quiet2_end, n));
    const durable::DurableStats st = store->stats();
    out.lock_ms = st.last_snapshot_lock_ms;
    out.snapshot_s = st.last_snapshot_seconds;
    store.reset();
    eng.reset();
    std::filesystem::remove_all(dir);
    return out;
}

void bench_stall(int runs) {
    std::printf("stall: 1M instances, 1 editor thread applying one-edit batches back to back, a "
                "snapshot written meanwhile; %d runs, median\n",
                runs);
    std::vector<double> with, without, lock, total;
    for (int r = 0; r < runs; ++r) {
        const StallResult s = run_stall();
        std::printf("    run %d: longest apply %.2f ms during the snapshot, %.2f ms without; "
                    "lock %.2f ms; snapshot %.2f s\n",
                    r + 1, s.with_snapshot_ms, s.without_ms, s.lock_ms, s.snapshot_s);
        with.push_back(s.with_snapshot_ms);
        without.push_back(s.without_ms);
        lock.push_back(s.lock_ms);
        total.push_back(s.snapshot_s);
    }
    std::printf("  longest edit stall: %.2f ms during a snapshot, %.2f ms without (baseline); "
                "snapshot lock %.2f ms; snapshot %.2f s\n",
                median(with), median(without), median(lock), median(total));
}

// Step: the lock a snapshot jump holds ------------------------------------------------------

struct ReplaceResult {
    double lock_ms = 0;          ///< the swap's exclusive hold (SnapshotReplace::lock_ms)
    double load_ms = 0;          ///< the new scene built aside
    double replace_s = 0;        ///< replace_scene in all (the snapshot file written and fsynced)
    double longest_read_ms = 0;  ///< the longest read() overlapping the replace
    double quiet_read_ms = 0;    ///< the longest read() in as long a window without one
    double restore_s = 0;        ///< baseline: restore_snapshot into an empty engine
    double first_commit_s = 0;   ///< the build after the swap (the next render pays it)
};

ReplaceResult run_replace(const std::string& snapshot) {
    auto eng = engine();
    const std::string dir = temp_dir();
    auto store = store_without_snapshots(*eng, dir, durable::StoreOptions{}.journal.mode);
    // The old scene: 1M instances laid out differently, built.
    for (auto& b : million_instances()) {
        for (Edit& e : b.edits)
            if (auto* i = std::get_if<AddInstance>(&e)) i->transform.m[7] = 3.0f;
        if (!eng->apply(std::move(b))) std::abort();
    }
    if (!eng->commit()) std::abort();

    // Reads take about a microsecond: only those over 50 us are kept (0 below means none was).
    std::vector<Span> spans;
    spans.reserve(1 << 20);
    std::atomic<bool> stop{false};
    std::thread reader([&] {
        while (!stop.load(std::memory_order_relaxed) && spans.size() < spans.capacity()) {
            const auto t0 = Clock::now();
            (void)eng->read([](const Scene& s) { return s.version(); });
            const auto t1 = Clock::now();
            if (t1 - t0 > std::chrono::microseconds(50)) spans.push_back({t0, t1});
        }
    });
    auto longest = [&](Clock::time_point a, Clock::time_point b, std::size_t upto) {
        double worst = 0;
        for (std::size_t i = 0; i < upto; ++i)
            if (spans[i].end >= a && spans[i].begin <= b)
                worst = std::max(worst, std::chrono::duration<double, std::milli>(
                                            spans[i].end - spans[i].begin)
                                            .count());
        return worst;
    };
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const auto begin = Clock::now();
    auto replaced = store->replace_scene(snapshot);
    if (!replaced) {
        std::fprintf(stderr, "replace failed: %s\n", replaced.error().describe().c_str());
        std::abort();
    }
    const auto end = Clock::now();
    const auto quiet_begin = Clock::now();
    std::this_thread::sleep_for(end - begin);
    const auto quiet_end = Clock::now();
    stop = true;
    reader.join();
    ReplaceResult out;
    out.lock_ms = replaced->lock_ms;
    out.load_ms = replaced->load_ms;
    out.replace_s = std::chrono::duration<double>(end - begin).count();
    out.longest_read_ms = longest(begin, end, spans.size());
    out.quiet_read_ms = longest(quiet_begin, quiet_end, spans.size());
    Stopwatch build;
    if (!eng->commit()) std::abort();
    out.first_commit_s = build.ms() / 1000.0;
    store.reset();
    eng.reset();
    std::filesystem::remove_all(dir);

    auto empty = engine();
    auto view = durable::open_snapshot(snapshot);
    if (!view) std::abort();
    Stopwatch restore;
    if (!empty->restore_snapshot(view->payload, view->version)) std::abort();
    out.restore_s = restore.ms() / 1000.0;
    return out;
}

/// `image` with every bulk add written as its single add_instance edits.
EditBatch one_edit_per_instance(const EditBatch& image) {
    EditBatch out;
    for (const Edit& e : image.edits) {
        if (const auto* bulk = std::get_if<AddInstances>(&e)) {
            for (Edit& one : test::singles(*bulk)) out.edits.push_back(std::move(one));
        } else {
            out.edits.push_back(e);
        }
    }
    return out;
}

void bench_image(int runs) {
    std::printf("image: a 1M-instance scene's snapshot, packed (now) against one add_instance per "
                "instance (baseline); %d runs, median\n",
                runs);
    auto eng = engine();
    for (auto& b : million_instances())
        if (!eng->apply(std::move(b))) std::abort();
    const uint64_t version = eng->version();
    struct Form {
        const char* name;
        std::string bytes;
        std::vector<double> encode_ms, restore_s;
    } forms[2] = {{"packed (bulk adds)", {}, {}, {}}, {"one add_instance each", {}, {}, {}}};
    std::vector<double> image_ms;
    for (int r = 0; r < runs; ++r) {
        Stopwatch clock;
        const EditBatch image = eng->read([](const Scene& sc) { return sc.to_batch(); });
        image_ms.push_back(clock.ms());
        const EditBatch batches[2] = {image, one_edit_per_instance(image)};
        for (int f = 0; f < 2; ++f) {
            Stopwatch encode;
            forms[f].bytes = durable::encode_snapshot(batches[f], version);
            forms[f].encode_ms.push_back(encode.ms());
            auto empty = engine();
            auto view = durable::open_snapshot(forms[f].bytes);
            if (!view) std::abort();
            Stopwatch restore;
            if (!empty->restore_snapshot(view->payload, view->version)) std::abort();
            forms[f].restore_s.push_back(restore.ms() / 1000.0);
        }
    }
    std::printf("  SceneImage::to_batch (packing included) %.1f ms\n", median(image_ms));
    for (Form& f : forms)
        std::printf("  %-22s %7.1f MB   encode %7.1f ms   restore_snapshot %5.2f s\n",
                    f.name, double(f.bytes.size()) / 1e6, median(f.encode_ms),
                    median(f.restore_s));
}

void bench_replace(int runs) {
    std::printf("replace: a built 1M-instance scene replaced by another 1M-instance scene's "
                "snapshot through a DurableStore (fsync always), 1 reader thread; %d runs, "
                "median\n",
                runs);
    std::string snapshot;
    {
        auto source = engine();
        for (auto& b : million_instances())
            if (!source->apply(std::move(b))) std::abort();
        snapshot = source->read(
            [](const Scene& s) { return durable::encode_snapshot(s.to_batch(), s.version() + 50); });
    }
    std::vector<double> lock, load, total, longest, quiet, restore, build;
    for (int r = 0; r < runs; ++r) {
        const ReplaceResult x = run_replace(snapshot);
        std::printf("    run %d: lock %.3f ms; load aside %.2f s; replace %.2f s; longest read "
                    "%.2f ms during, %.2f ms without; restore into an empty engine %.2f s; "
                    "first commit %.2f s\n",
                    r + 1, x.lock_ms, x.load_ms / 1000.0, x.replace_s, x.longest_read_ms,
                    x.quiet_read_ms, x.restore_s, x.first_commit_s);
        lock.push_back(x.lock_ms);
        load.push_back(x.load_ms / 1000.0);
        total.push_back(x.replace_s);
        longest.push_back(x.longest_read_ms);
        quiet.push_back(x.quiet_read_ms);
        restore.push_back(x.restore_s);
        build.push_back(x.first_commit_s);
    }
    std::printf("  scene lock held %.3f ms by the swap (%.0f MB snapshot); built aside in %.2f s, "
                "replace %.2f s in all; longest read %.2f ms during the replace, %.2f ms without "
                "(baseline); restore_snapshot (the lock held while loading) %.2f s; first commit "
                "after the swap %.2f s\n",
                median(lock), double(snapshot.size()) / 1e6, median(load), median(total),
                median(longest), median(quiet), median(restore), median(build));
}

}  // namespace
}  // namespace strata

int main(int argc, char** argv) {
    spdlog::set_level(spdlog::level::warn);
    const std::string what = argc > 1 ? argv[1] : "all";
    const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 3;
    std::printf("machine: %u hardware threads\n", std::thread::hardware_concurrency());
    if (what == "edits" || what == "all") strata::bench_edits(runs);
    if (what == "restart" || what == "all") strata::bench_restart(runs);
    if (what == "stall" || what == "all") strata::bench_stall(runs);
    if (what == "replace" || what == "all") strata::bench_replace(runs);
    if (what == "image" || what == "all") strata::bench_image(runs);
    return 0;
}
