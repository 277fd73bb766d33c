#include "core/shader/SpirvReflect.h"

#include <algorithm>
#include <array>
#include <cstdio>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

namespace loom {

namespace {

// The handful of SPIR-V enum values we need. Defined locally so the core library does
// not depend on glslang/SPIRV-Headers being installed.
namespace spv {
constexpr uint32_t MagicNumber = 0x07230203u;
constexpr uint32_t MagicNumberSwapped = 0x03022307u;
constexpr uint32_t HeaderWords = 5;

constexpr uint32_t OpName = 5;
constexpr uint32_t OpMemberName = 6;
constexpr uint32_t OpEntryPoint = 15;
constexpr uint32_t OpExecutionMode = 16;
constexpr uint32_t OpTypeVoid = 19;
constexpr uint32_t OpTypeBool = 20;
constexpr uint32_t OpTypeInt = 21;
constexpr uint32_t OpTypeFloat = 22;
constexpr uint32_t OpTypeVector = 23;
constexpr uint32_t OpTypeMatrix = 24;
constexpr uint32_t OpTypeImage = 25;
constexpr uint32_t OpTypeSampler = 26;
constexpr uint32_t OpTypeSampledImage = 27;
constexpr uint32_t OpTypeArray = 28;
constexpr uint32_t OpTypeRuntimeArray = 29;
constexpr uint32_t OpTypeStruct = 30;
constexpr uint32_t OpTypePointer = 32;
constexpr uint32_t OpTypeForwardPointer = 39;
constexpr uint32_t OpConstant = 43;
constexpr uint32_t OpConstantComposite = 44;
constexpr uint32_t OpSpecConstant = 50;
constexpr uint32_t OpSpecConstantComposite = 51;
constexpr uint32_t OpVariable = 59;
constexpr uint32_t OpDecorate = 71;
constexpr uint32_t OpMemberDecorate = 72;
constexpr uint32_t OpExecutionModeId = 331;

constexpr uint32_t ExecutionModelGLCompute = 5;
constexpr uint32_t ExecutionModeLocalSize = 17;
constexpr uint32_t ExecutionModeLocalSizeId = 38;

constexpr uint32_t StorageClassUniformConstant = 0;
constexpr uint32_t StorageClassUniform = 2;
constexpr uint32_t StorageClassPushConstant = 9;
constexpr uint32_t StorageClassStorageBuffer = 12;

constexpr uint32_t DecorationBlock = 2;
constexpr uint32_t DecorationBufferBlock = 3;
constexpr uint32_t DecorationRowMajor = 4;
constexpr uint32_t DecorationArrayStride = 6;
constexpr uint32_t DecorationMatrixStride = 7;
constexpr uint32_t DecorationBuiltIn = 11;
constexpr uint32_t DecorationNonWritable = 24;
constexpr uint32_t DecorationBinding = 33;
constexpr uint32_t DecorationDescriptorSet = 34;
constexpr uint32_t DecorationOffset = 35;

constexpr uint32_t BuiltInWorkgroupSize = 25;

constexpr uint32_t DimBuffer = 5;

constexpr uint32_t ImageFormatRgba32f = 1;
constexpr uint32_t ImageFormatRgba16f = 2;
constexpr uint32_t ImageFormatR32f = 3;
constexpr uint32_t ImageFormatRgba8 = 4;
constexpr uint32_t ImageFormatRg32f = 6;
constexpr uint32_t ImageFormatRg16f = 7;
constexpr uint32_t ImageFormatR32i = 24;
constexpr uint32_t ImageFormatR32ui = 33;
}  // namespace spv

// Guards type recursion against cyclic (malformed) type graphs.
constexpr int MaxTypeDepth = 64;

[[noreturn]] void fail(const std::string& message) {
    throw std::runtime_error("SPIR-V reflection: " + message);
}

std::string hex(uint32_t value) {
    char buf[16];
    std::snprintf(buf, sizeof(buf), "0x%08x", value);
    return buf;
}

uint32_t byteSwap(uint32_t v) {
    return ((v & 0xffu) << 24) | ((v & 0xff00u) << 8) | ((v >> 8) & 0xff00u) | (v >> 24);
}

const char* imageFormatName(uint32_t format) {
    switch (format) {
        case spv::ImageFormatRgba32f:
            return "rgba32f";
        case spv::ImageFormatRgba16f:
            return "rgba16f";
        case spv::ImageFormatR32f:
            return "r32f";
        case spv::ImageFormatRgba8:
            return "rgba8";
        case spv::ImageFormatRg32f:
            return "rg32f";
        case spv::ImageFormatRg16f:
            return "rg16f";
        case spv::ImageFormatR32i:
            return "r32i";
        case spv::ImageFormatR32ui:
            return "r32ui";
        default:
            return "unknown";
    }
}

// View of one instruction's operands (the words after the opcode/word-count word).
struct Instruction {
    uint32_t opcode = 0;
    size_t position = 0;  // word index in the module, for error messages
    const uint32_t* operands = nullptr;
    uint32_t operandCount = 0;

    uint32_t operand(uint32_t index) const {
        if (index >= operandCount) {
            fail("instruction at word " + std::to_string(position) + " (opcode " +
                 std::to_string(opcode) + ") has too few operands");
        }
        return operands[index];
    }

    // Decodes a nul-terminated UTF-8 literal packed little-endian into words.
    std::string string(uint32_t index) const {
        std::string out;
        for (uint32_t i = index; i < operandCount; ++i) {
            for (int byte = 0; byte < 4; ++byte) {
                const char c = static_cast<char>((operands[i] >> (8 * byte)) & 0xffu);
                if (c == '\0') {
                    return out;
                }
                out.push_back(c);
            }
        }
        fail("instruction at word " + std::to_string(position) + " (opcode " +
             std::to_string(opcode) + ") has an unterminated string literal");
    }
};

struct Decorations {
    std::optional<uint32_t> binding;
    std::optional<uint32_t> set;
    std::optional<uint32_t> offset;
    std::optional<uint32_t> arrayStride;
    std::optional<uint32_t> matrixStride;
    std::optional<uint32_t> builtIn;
    bool block = false;
    bool bufferBlock = false;
    bool nonWritable = false;
    bool rowMajor = false;

    void apply(uint32_t decoration, const Instruction& inst, uint32_t literalIndex) {
        switch (decoration) {
            case spv::DecorationBinding:
                binding = inst.operand(literalIndex);
                break;
            case spv::DecorationDescriptorSet:
                set = inst.operand(literalIndex);
                break;
            case spv::DecorationOffset:
                offset = inst.operand(literalIndex);
                break;
            case spv::DecorationArrayStride:
                arrayStride = inst.operand(literalIndex);
                break;
            case spv::DecorationMatrixStride:
                matrixStride = inst.operand(literalIndex);
                break;
            case spv::DecorationBuiltIn:
                builtIn = inst.operand(literalIndex);
                break;
            case spv::DecorationBlock:
                block = true;
                break;
            case spv::DecorationBufferBlock:
                bufferBlock = true;
                break;
            case spv::DecorationNonWritable:
                nonWritable = true;
                break;
            case spv::DecorationRowMajor:
                rowMajor = true;
                break;
            default:
                break;
        }
    }
};

struct TypeInfo {
    uint32_t opcode = 0;
    std::vector<uint32_t> operands;  // operands after the result id
};

struct Variable {
    uint32_t id = 0;
    uint32_t pointerType = 0;
    uint32_t storageClass = 0;
};

uint64_t memberKey(uint32_t structId, uint32_t member) {
    return (static_cast<uint64_t>(structId) << 32) | member;
}

class SpirvModule {
public:
    explicit SpirvModule(const std::vector<uint32_t>& words) { parse(words); }

    ShaderReflection reflect() const {
        ShaderReflection result;
        for (const Variable& var : mVariables) {
            switch (var.storageClass) {
                case spv::StorageClassUniformConstant:
                case spv::StorageClassUniform:
                case spv::StorageClassStorageBuffer: {
                    // Resources no function touches are dead (a library's buffers a kernel
                    // never reads; glslang gives them binding 0) and need no descriptor.
                    if (mHasFunctions && !mUsedPointers.count(var.id)) break;
                    result.bindings.push_back(reflectBinding(var));
                    break;
                }
                case spv::StorageClassPushConstant:
                    // Only one push-constant block is allowed per entry point; keep the first.
                    if (!result.pushConstants) {
                        result.pushConstants = reflectPushConstants(var);
                    }
                    break;
                default:
                    break;
            }
        }
        std::stable_sort(result.bindings.begin(), result.bindings.end(),
                         [](const ReflectedBinding& a, const ReflectedBinding& b) {
                             return a.set != b.set ? a.set < b.set : a.binding < b.binding;
                         });
        resolveLocalSize(result.localSize);
        return result;
    }

private:
    void parse(const std::vector<uint32_t>& input) {
        if (input.size() < spv::HeaderWords) {
            fail("module too short: " + std::to_string(input.size()) +
                 " words, the header alone needs " + std::to_string(spv::HeaderWords));
        }
        const std::vector<uint32_t>* words = &input;
        std::vector<uint32_t> swapped;
        if (input[0] == spv::MagicNumberSwapped) {
            // Module was written with the opposite endianness; normalise it.
            swapped.reserve(input.size());
            for (uint32_t w : input) {
                swapped.push_back(byteSwap(w));
            }
            words = &swapped;
        } else if (input[0] != spv::MagicNumber) {
            fail("bad magic number " + hex(input[0]) + " (expected " + hex(spv::MagicNumber) + ")");
        }

        size_t pos = spv::HeaderWords;
        while (pos < words->size()) {
            const uint32_t first = (*words)[pos];
            const uint32_t wordCount = first >> 16;
            Instruction inst;
            inst.opcode = first & 0xffffu;
            inst.position = pos;
            if (wordCount == 0) {
                fail("instruction at word " + std::to_string(pos) + " (opcode " +
                     std::to_string(inst.opcode) + ") has a word count of zero");
            }
            if (wordCount > words->size() - pos) {
                fail("truncated module: instruction at word " + std::to_string(pos) + " (opcode " +
                     std::to_string(inst.opcode) + ") needs " + std::to_string(wordCount) +
                     " words but only " + std::to_string(words->size() - pos) + " remain");
            }
            inst.operands = words->data() + pos + 1;
            inst.operandCount = wordCount - 1;
            handle(inst);
            pos += wordCount;
        }
    }

    // Records the pointer operands through which function bodies use global variables.
    void notePointerUse(const Instruction& inst) {
        const uint32_t op = inst.opcode;
        auto use = [&](size_t i) {
            if (i < inst.operandCount) mUsedPointers.insert(inst.operand(i));
        };
        if (op == 54) mHasFunctions = true;  // OpFunction
        switch (op) {
            case 60: case 61: case 65: case 66: case 67: case 68:  // texel ptr, load, chains, length
                use(2);
                break;
            case 62: case 228:  // OpStore, OpAtomicStore
                use(0);
                break;
            case 63:  // OpCopyMemory
                use(0);
                use(1);
                break;
            case 57:  // OpFunctionCall: arguments
                for (size_t i = 3; i < inst.operandCount; ++i) use(i);
                break;
            default:
                if (op >= 227 && op <= 242) use(2);  // atomics
                break;
        }
    }

    void handle(const Instruction& inst) {
        const uint32_t op = inst.opcode;
        notePointerUse(inst);
        switch (op) {
            case spv::OpName:
                mNames[inst.operand(0)] = inst.string(1);
                break;
            case spv::OpMemberName:
                mMemberNames[memberKey(inst.operand(0), inst.operand(1))] = inst.string(2);
                break;
            case spv::OpEntryPoint:
                if (!mEntryPoint ||
                    (!mEntryIsCompute && inst.operand(0) == spv::ExecutionModelGLCompute)) {
                    mEntryPoint = inst.operand(1);
                    mEntryIsCompute = inst.operand(0) == spv::ExecutionModelGLCompute;
                }
                break;
            case spv::OpExecutionMode:
            case spv::OpExecutionModeId: {
                const uint32_t mode = inst.operand(1);
                if (mode == spv::ExecutionModeLocalSize || mode == spv::ExecutionModeLocalSizeId) {
                    LocalSizeMode& entry = mLocalSizes[inst.operand(0)];
                    entry.isId = mode == spv::ExecutionModeLocalSizeId;
                    for (uint32_t i = 0; i < 3; ++i) {
                        entry.values[i] = inst.operand(2 + i);
                    }
                }
                break;
            }
            case spv::OpDecorate:
                mDecorations[inst.operand(0)].apply(inst.operand(1), inst, 2);
                break;
            case spv::OpMemberDecorate:
                mMemberDecorations[memberKey(inst.operand(0), inst.operand(1))].apply(
                    inst.operand(2), inst, 3);
                break;
            case spv::OpConstant:
            case spv::OpSpecConstant:
                // Low 32 bits are enough for array lengths and workgroup sizes.
                mConstants[inst.operand(1)] = inst.operand(2);
                break;
            case spv::OpConstantComposite:
            case spv::OpSpecConstantComposite:
                mComposites[inst.operand(1)].assign(inst.operands + 2,
                                                    inst.operands + inst.operandCount);
                break;
            case spv::OpVariable:
                mVariables.push_back({inst.operand(1), inst.operand(0), inst.operand(2)});
                break;
            default:
                // Type declarations all carry their result id first.
                if (op >= spv::OpTypeVoid && op < spv::OpTypeForwardPointer) {
                    TypeInfo& type = mTypes[inst.operand(0)];
                    type.opcode = op;
                    type.operands.assign(inst.operands + 1, inst.operands + inst.operandCount);
                }
                break;
        }
    }

    const TypeInfo* type(uint32_t id) const {
        auto it = mTypes.find(id);
        return it == mTypes.end() ? nullptr : &it->second;
    }

    // Operand of a type instruction; throws instead of reading past the stored operands.
    static uint32_t typeOperand(const TypeInfo& t, size_t index) {
        if (index >= t.operands.size()) {
            fail("type declaration (opcode " + std::to_string(t.opcode) + ") has too few operands");
        }
        return t.operands[index];
    }

    std::string name(uint32_t id) const {
        auto it = mNames.find(id);
        return it == mNames.end() ? std::string() : it->second;
    }

    const Decorations* decorations(uint32_t id) const {
        auto it = mDecorations.find(id);
        return it == mDecorations.end() ? nullptr : &it->second;
    }

    const Decorations* memberDecorations(uint32_t structId, uint32_t member) const {
        auto it = mMemberDecorations.find(memberKey(structId, member));
        return it == mMemberDecorations.end() ? nullptr : &it->second;
    }

    std::optional<uint32_t> constant(uint32_t id) const {
        auto it = mConstants.find(id);
        return it == mConstants.end() ? std::nullopt : std::optional<uint32_t>(it->second);
    }

    // Byte size of a type as laid out in a block. Runtime arrays count as zero.
    uint32_t sizeOf(uint32_t typeId, const Decorations* memberDecor, int depth) const {
        if (depth > MaxTypeDepth) {
            fail("type nesting too deep (cyclic type definitions?)");
        }
        const TypeInfo* t = type(typeId);
        if (!t) {
            return 0;
        }
        switch (t->opcode) {
            case spv::OpTypeBool:
                return 4;  // bools in blocks are 32-bit
            case spv::OpTypeInt:
            case spv::OpTypeFloat:
                return typeOperand(*t, 0) / 8;
            case spv::OpTypeVector:
                return typeOperand(*t, 1) * sizeOf(typeOperand(*t, 0), nullptr, depth + 1);
            case spv::OpTypeMatrix: {
                const uint32_t columnType = typeOperand(*t, 0);
                const uint32_t columns = typeOperand(*t, 1);
                if (memberDecor && memberDecor->matrixStride) {
                    // Row-major strides step between rows, column-major between columns.
                    uint32_t vectors = columns;
                    if (memberDecor->rowMajor) {
                        const TypeInfo* col = type(columnType);
                        vectors = col && col->opcode == spv::OpTypeVector ? typeOperand(*col, 1)
                                                                          : columns;
                    }
                    return vectors * *memberDecor->matrixStride;
                }
                return columns * sizeOf(columnType, nullptr, depth + 1);
            }
            case spv::OpTypeArray: {
                const uint32_t length = constant(typeOperand(*t, 1)).value_or(0);
                const Decorations* d = decorations(typeId);
                const uint32_t stride = d && d->arrayStride
                                            ? *d->arrayStride
                                            : sizeOf(typeOperand(*t, 0), memberDecor, depth + 1);
                return length * stride;
            }
            case spv::OpTypeStruct: {
                // Memoised so widely shared nested structs cannot blow up exponentially.
                if (auto it = mStructSizes.find(typeId); it != mStructSizes.end()) {
                    return it->second;
                }
                uint32_t size = 0;
                for (uint32_t i = 0; i < t->operands.size(); ++i) {
                    const Decorations* md = memberDecorations(typeId, i);
                    const uint32_t offset = md && md->offset ? *md->offset : 0;
                    size = std::max(size, offset + sizeOf(t->operands[i], md, depth + 1));
                }
                mStructSizes[typeId] = size;
                return size;
            }
            default:
                return 0;
        }
    }

    // GLSL-style name for the scalar/vector/matrix types a push-constant block typically holds.
    std::string typeName(uint32_t typeId) const {
        const TypeInfo* t = type(typeId);
        if (!t) {
            return "other";
        }
        auto scalarPrefix = [this](uint32_t scalarId) -> std::optional<std::string> {
            const TypeInfo* s = type(scalarId);
            if (!s) {
                return std::nullopt;
            }
            if (s->opcode == spv::OpTypeFloat && typeOperand(*s, 0) == 32) {
                return "";
            }
            if (s->opcode == spv::OpTypeInt && typeOperand(*s, 0) == 32) {
                return typeOperand(*s, 1) ? "i" : "u";
            }
            return std::nullopt;
        };
        switch (t->opcode) {
            case spv::OpTypeBool:
                return "bool";
            case spv::OpTypeFloat:
                return typeOperand(*t, 0) == 32 ? "float" : "other";
            case spv::OpTypeInt:
                if (typeOperand(*t, 0) != 32) {
                    return "other";
                }
                return typeOperand(*t, 1) ? "int" : "uint";
            case spv::OpTypeVector: {
                const uint32_t count = typeOperand(*t, 1);
                const auto prefix = scalarPrefix(typeOperand(*t, 0));
                if (!prefix || count < 2 || count > 4) {
                    return "other";
                }
                return *prefix + "vec" + std::to_string(count);
            }
            case spv::OpTypeMatrix: {
                const TypeInfo* col = type(typeOperand(*t, 0));
                if (typeOperand(*t, 1) == 4 && col && col->opcode == spv::OpTypeVector &&
                    typeOperand(*col, 1) == 4 &&
                    scalarPrefix(typeOperand(*col, 0)) == std::string()) {
                    return "mat4";
                }
                return "other";
            }
            default:
                return "other";
        }
    }

    uint32_t pointee(const Variable& var) const {
        const TypeInfo* ptr = type(var.pointerType);
        if (!ptr || ptr->opcode != spv::OpTypePointer) {
            fail("variable %" + std::to_string(var.id) + " does not have a pointer type");
        }
        return typeOperand(*ptr, 1);
    }

    ReflectedBinding reflectBinding(const Variable& var) const {
        ReflectedBinding b;
        uint32_t typeId = pointee(var);

        // Peel (possibly nested) descriptor arrays; 0 marks a runtime or unknown size.
        for (int depth = 0;; ++depth) {
            if (depth > MaxTypeDepth) {
                fail("array nesting too deep (cyclic type definitions?)");
            }
            const TypeInfo* t = type(typeId);
            if (t && t->opcode == spv::OpTypeArray) {
                b.arraySize *= constant(typeOperand(*t, 1)).value_or(0);
            } else if (t && t->opcode == spv::OpTypeRuntimeArray) {
                b.arraySize = 0;
            } else {
                break;
            }
            typeId = typeOperand(*t, 0);
        }

        const Decorations* varDecor = decorations(var.id);
        if (varDecor) {
            b.set = varDecor->set.value_or(0);
            b.binding = varDecor->binding.value_or(0);
            b.readonly = varDecor->nonWritable;
        }

        const TypeInfo* t = type(typeId);
        const uint32_t opcode = t ? t->opcode : 0;
        if (opcode == spv::OpTypeStruct) {
            b.blockName = name(typeId);
            const Decorations* structDecor = decorations(typeId);
            if (var.storageClass == spv::StorageClassStorageBuffer) {
                b.kind = DescriptorKind::StorageBuffer;
            } else if (var.storageClass == spv::StorageClassUniform) {
                // Pre-SPIR-V-1.3 SSBOs are Uniform-storage structs decorated BufferBlock.
                b.kind = structDecor && structDecor->bufferBlock ? DescriptorKind::StorageBuffer
                                                                 : DescriptorKind::UniformBuffer;
            }
            bool allMembersReadonly = !t->operands.empty();
            for (uint32_t i = 0; i < t->operands.size(); ++i) {
                const Decorations* md = memberDecorations(typeId, i);
                allMembersReadonly = allMembersReadonly && md && md->nonWritable;
            }
            b.readonly = b.readonly || allMembersReadonly;
            b.members = reflectMembers(typeId, b.blockSize);
            if (!t->operands.empty()) {
                const TypeInfo* last = type(t->operands.back());
                if (last && last->opcode == spv::OpTypeRuntimeArray) {
                    const Decorations* md = memberDecorations(typeId, uint32_t(t->operands.size() - 1));
                    const Decorations* ad = decorations(t->operands.back());
                    b.runtimeArrayOffset = md && md->offset ? *md->offset : 0;
                    b.runtimeArrayStride = ad && ad->arrayStride ? *ad->arrayStride : 0;
                }
            }
        } else if (opcode == spv::OpTypeImage) {
            const uint32_t dim = typeOperand(*t, 1);
            const uint32_t sampled = typeOperand(*t, 5);
            // Texel buffers need their own Vulkan descriptor types, so leave them Unknown.
            if (sampled == 2 && dim != spv::DimBuffer) {
                b.kind = DescriptorKind::StorageImage;
                b.imageFormat = imageFormatName(typeOperand(*t, 6));
            }
        } else if (opcode == spv::OpTypeSampledImage) {
            b.kind = DescriptorKind::SampledImage;
        } else if (opcode == spv::OpTypeSampler) {
            b.kind = DescriptorKind::Sampler;
        }

        b.name = name(var.id);
        if (b.name.empty()) {
            b.name = b.blockName.empty() ? name(typeId) : b.blockName;
        }
        return b;
    }

    // Members of a block type with their offsets, sizes and types; `size` gets the block's
    // extent (runtime arrays count 0).
    std::vector<ReflectedMember> reflectMembers(uint32_t typeId, uint32_t& size) const {
        std::vector<ReflectedMember> members;
        const TypeInfo* t = type(typeId);
        if (!t || t->opcode != spv::OpTypeStruct) return members;
        for (uint32_t i = 0; i < t->operands.size(); ++i) {
            const Decorations* md = memberDecorations(typeId, i);
            ReflectedMember m;
            auto nameIt = mMemberNames.find(memberKey(typeId, i));
            if (nameIt != mMemberNames.end()) m.name = nameIt->second;
            m.offset = md && md->offset ? *md->offset : 0;
            m.size = sizeOf(t->operands[i], md, 0);
            m.type = typeName(t->operands[i]);
            size = std::max(size, m.offset + m.size);
            members.push_back(std::move(m));
        }
        return members;
    }

    ReflectedPushConstants reflectPushConstants(const Variable& var) const {
        ReflectedPushConstants pc;
        const uint32_t typeId = pointee(var);
        pc.blockName = name(typeId);
        pc.members = reflectMembers(typeId, pc.size);
        return pc;
    }

    void resolveLocalSize(uint32_t (&out)[3]) const {
        // A WorkgroupSize built-in constant overrides the LocalSize execution modes.
        for (const auto& [id, constituents] : mComposites) {
            const Decorations* d = decorations(id);
            if (d && d->builtIn == spv::BuiltInWorkgroupSize && constituents.size() == 3) {
                for (size_t i = 0; i < 3; ++i) {
                    out[i] = constant(constituents[i]).value_or(1);
                }
                return;
            }
        }
        const LocalSizeMode* mode = nullptr;
        if (mEntryPoint) {
            auto it = mLocalSizes.find(*mEntryPoint);
            mode = it == mLocalSizes.end() ? nullptr : &it->second;
        }
        if (!mode && !mLocalSizes.empty()) {
            mode = &mLocalSizes.begin()->second;
        }
        if (!mode) {
            return;
        }
        for (size_t i = 0; i < 3; ++i) {
            out[i] = mode->isId ? constant(mode->values[i]).value_or(1) : mode->values[i];
        }
    }

    struct LocalSizeMode {
        bool isId = false;
        std::array<uint32_t, 3> values{1, 1, 1};
    };

    std::unordered_map<uint32_t, std::string> mNames;
    std::unordered_map<uint64_t, std::string> mMemberNames;
    std::unordered_map<uint32_t, Decorations> mDecorations;
    std::unordered_map<uint64_t, Decorations> mMemberDecorations;
    std::unordered_map<uint32_t, TypeInfo> mTypes;
    std::unordered_map<uint32_t, uint32_t> mConstants;
    std::unordered_map<uint32_t, std::vector<uint32_t>> mComposites;
    std::unordered_map<uint32_t, LocalSizeMode> mLocalSizes;  // keyed by entry point id
    std::vector<Variable> mVariables;
    mutable std::unordered_map<uint32_t, uint32_t> mStructSizes;  // sizeOf cache
    std::optional<uint32_t> mEntryPoint;  // first GLCompute entry point, else the first one
    bool mEntryIsCompute = false;
    bool mHasFunctions = false;
    std::unordered_set<uint32_t> mUsedPointers;  // ids used as pointers inside functions
};

}  // namespace

const ReflectedBinding* ShaderReflection::find(std::string_view name) const {
    // Instance names win over block names so "inBuf" never resolves to another block's type.
    for (const ReflectedBinding& b : bindings) {
        if (b.name == name) {
            return &b;
        }
    }
    for (const ReflectedBinding& b : bindings) {
        if (!b.blockName.empty() && b.blockName == name) {
            return &b;
        }
    }
    return nullptr;
}

const char* toString(DescriptorKind kind) {
    switch (kind) {
        case DescriptorKind::StorageImage:
            return "StorageImage";
        case DescriptorKind::SampledImage:
            return "SampledImage";
        case DescriptorKind::UniformBuffer:
            return "UniformBuffer";
        case DescriptorKind::StorageBuffer:
            return "StorageBuffer";
        case DescriptorKind::Sampler:
            return "Sampler";
        case DescriptorKind::Unknown:
            break;
    }
    return "Unknown";
}

ShaderReflection reflectSpirv(const std::vector<uint32_t>& words) {
    return SpirvModule(words).reflect();
}

}  // namespace loom
