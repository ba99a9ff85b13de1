// The id index against std::unordered_map under random inserts and erases (probe runs that wrap
// around the table's end and shift back on erase included), and what it holds per id.

#include "engine/core/id_index.h"

#include <random>
#include <string>
#include <unordered_map>

#include <gtest/gtest.h>

#include "engine/core/handle.h"

namespace strata {
namespace {

struct Record {
    std::string id;
};
struct RecordTag;
using RecordHandle = Handle<RecordTag>;

TEST(IdIndex, AgreesWithAMapUnderRandomInsertsAndErases) {
    SlotArray<Record, RecordTag> records;
    IdIndex<RecordHandle> index;
    std::unordered_map<std::string, RecordHandle> expected;
    std::mt19937 rng(7);
    for (int step = 0; step < 200000; ++step) {
        // Few distinct ids and a table that stays small: long probe runs, frequent wraps.
        const std::string id = "id-" + std::to_string(rng() % 3000);
        const RecordHandle found = index.find(id, records);
        auto it = expected.find(id);
        ASSERT_EQ(found, it == expected.end() ? RecordHandle{} : it->second) << id;
        if (it == expected.end()) {
            const RecordHandle h = records.insert(Record{id});
            index.insert(id, h);
            expected.emplace(id, h);
        } else if (rng() % 2 == 0) {
            ASSERT_TRUE(index.erase(id, it->second));
            EXPECT_FALSE(index.erase(id, it->second));
            records.erase(it->second);
            expected.erase(it);
        }
        ASSERT_EQ(index.size(), expected.size());
    }
    for (const auto& [id, h] : expected) EXPECT_EQ(index.find(id, records), h) << id;
    EXPECT_TRUE(index.find("never-added", records).is_null());
}

TEST(IdIndex, AnEntryWhoseRecordIsGoneIsNotFound) {
    SlotArray<Record, RecordTag> records;
    IdIndex<RecordHandle> index;
    const RecordHandle h = records.insert(Record{"a"});
    index.insert("a", h);
    records.erase(h);
    EXPECT_TRUE(index.find("a", records).is_null());
    EXPECT_TRUE(index.erase("a", h));
    EXPECT_EQ(index.size(), 0u);
}

TEST(IdIndex, HoldsAMillionIdsInUnderThirtyBytesEach) {
    SlotArray<Record, RecordTag> records;
    IdIndex<RecordHandle> index;
    constexpr std::size_t N = 1'000'000;
    index.reserve(N);
    const std::size_t reserved = index.bytes();
    for (std::size_t i = 0; i < N; ++i) {
        std::string id = "b" + std::to_string(i);
        const RecordHandle h = records.insert(Record{id});
        index.insert(id, h);
    }
    EXPECT_EQ(index.bytes(), reserved) << "reserve() made room for all of them";
    EXPECT_LT(index.bytes() / N, 30u);
    EXPECT_EQ(index.find("b123456", records).index, 123456u);
}

}  // namespace
}  // namespace strata
