// The headless snapshot renderer (cullide/io/Snapshot.h): one non-indexed draw of every drawable triangle with its
// colour baked into the vertices, into an off-screen multisampled framebuffer, resolved by a blit and read back.
//
// Why this shape: llvmpipe costs ~0.2 ms per draw call, so the whole scene is one buffer and one draw; a
// non-indexed buffer lets every triangle carry its own colour (base / highlight / mark / faded) without a second
// lookup; the shader derives the flat normal and edge distances itself, so a vertex is 16 bytes.
#include "cullide/io/Snapshot.h"

#include "bindings.h"
#include "gl/EglContext.h"
#include "gl/GlApi.h"
#include "gl/GlProgram.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace cullide {
namespace gl {
namespace {

constexpr int kMaxSize = 8192;
/// Multisampling is skipped above this many pixels: 4 samples of colour and depth at 8192² would need 2 GiB.
constexpr long long kMaxMultisamplePixels = 4096LL * 4096LL;
/// 4x multisampling smooths the silhouettes of the figures and costs nothing on llvmpipe: 95K triangles at 640x480
/// took 65 ms with it and 92 ms without (its multisampled rasterizer path is the faster one for tiny triangles).
constexpr int kSamples = 4;
/// Non-highlighted triangles of a highlighted object keep this much of their colour (the rest is background).
constexpr float kDimmedOpacity = 0.3f;
constexpr float kEdgeDarkening = 0.35f;
/// The frame box fills the image up to this fraction (a thin margin around the objects).
constexpr double kFill = 1.0 / 1.06;

struct Vertex {
    float position[3];
    std::uint8_t rgba[4];
};
static_assert(sizeof(Vertex) == 16, "interleaved snapshot vertex: 3 floats + RGBA8");

constexpr std::uint8_t kBase = 0;
constexpr std::uint8_t kHighlighted = 1;
constexpr std::uint8_t kMarked = 2;


void requireColour(const std::array<float, 3>& c, const std::string& what) {
    for (float v : c) {
        if (!(v >= 0.0f && v <= 1.0f))  // also rejects NaN
            throw std::invalid_argument("SnapshotRenderer: " + what + " must have components in [0, 1]");
    }
}

void validateView(const SnapshotView& view) {
    if (view.width < 1 || view.width > kMaxSize || view.height < 1 || view.height > kMaxSize) {
        throw std::invalid_argument("SnapshotRenderer: image size must be 1..8192 in each direction, got " +
                                    std::to_string(view.width) + "x" + std::to_string(view.height));
    }
    if (!std::isfinite(view.azimuthDeg) || !std::isfinite(view.elevationDeg))
        throw std::invalid_argument("SnapshotRenderer: azimuth and elevation must be finite");
    if (view.frame && (!view.frame->isFinite() || view.frame->isEmpty()))
        throw std::invalid_argument("SnapshotRenderer: the frame box must be finite and not empty");
    requireColour(view.background, "the background colour");
    requireColour(view.highlight, "the highlight colour");
    requireColour(view.mark, "the mark colour");
}

std::uint8_t toByte(float v) { return static_cast<std::uint8_t>(std::lround(v * 255.0f)); }

/// A triangle is drawable when its indices are in range and its vertices finite.
bool drawable(const TriangleMesh& mesh, const TriangleIndices& t) {
    const std::size_t n = mesh.vertices.size();
    return t[0] < n && t[1] < n && t[2] < n && mesh.vertices[t[0]].allFinite() && mesh.vertices[t[1]].allFinite() &&
           mesh.vertices[t[2]].allFinite();
}

/// Orthographic camera: the basis, the fitted half extents and the depth range, all relative to `centre`.
struct Camera {
    Vec3 centre;
    Vec3 right, up, toViewer;
    double halfWidth = 1.0, halfHeight = 1.0;
    double zNear = 1.0, zFar = -1.0;  ///< along toViewer: zNear is the largest

    /// Depth range: everything drawn, not only the frame, so that geometry in front of the frame still occludes
    /// correctly (GL_DEPTH_CLAMP keeps what lies outside the frame's depth from being clipped).
    void setDepthRange(double zMin, double zMax) {
        const double pad = 0.01 * (zMax - zMin) + 1e-6 * std::max(halfWidth, halfHeight);
        zNear = zMax + pad;
        zFar = zMin - pad;
    }

    /// Row-major clip transform of centre-relative positions.
    void matrix(float m[16]) const {
        const double zRange = zNear - zFar;
        for (int c = 0; c < 3; ++c) {
            m[0 + c] = static_cast<float>(right[c] / halfWidth);
            m[4 + c] = static_cast<float>(up[c] / halfHeight);
            m[8 + c] = static_cast<float>(-2.0 * toViewer[c] / zRange);  // nearest (largest z) -> -1
            m[12 + c] = 0.0f;
        }
        m[3] = 0.0f;
        m[7] = 0.0f;
        m[11] = static_cast<float>((zNear + zFar) / zRange);
        m[15] = 1.0f;
    }
};

Camera fitCamera(const SnapshotView& view, const Aabb& frame) {
    constexpr double kDeg = 3.14159265358979323846 / 180.0;
    const double a = view.azimuthDeg * kDeg;
    const double e = view.elevationDeg * kDeg;
    Camera cam;
    cam.centre = 0.5 * (frame.min + frame.max);
    cam.toViewer = Vec3(std::cos(e) * std::sin(a), std::sin(e), std::cos(e) * std::cos(a));
    // Perpendicular to toViewer for every elevation, so looking straight down or up needs no special case.
    cam.right = Vec3(std::cos(a), 0.0, -std::sin(a));
    cam.up = cam.toViewer.cross(cam.right);

    double maxX = 0.0, maxY = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3 p(corner & 1 ? frame.max.x() : frame.min.x(), corner & 2 ? frame.max.y() : frame.min.y(),
                     corner & 4 ? frame.max.z() : frame.min.z());
        maxX = std::max(maxX, std::abs((p - cam.centre).dot(cam.right)));
        maxY = std::max(maxY, std::abs((p - cam.centre).dot(cam.up)));
    }
    // A point-like frame (one vertex, or a flat scene seen edge-on in both directions) still gives a valid camera
    // whose float matrix stays finite: the shown region is at least a little larger than the frame's rounding.
    const double size = std::max({maxX, maxY, 1e-9 * cam.centre.cwiseAbs().maxCoeff(), 1e-12});
    maxX = std::max(maxX, 1e-6 * size) / kFill;
    maxY = std::max(maxY, 1e-6 * size) / kFill;
    const double aspect = static_cast<double>(view.width) / view.height;
    cam.halfWidth = std::max(maxX, maxY * aspect);
    cam.halfHeight = cam.halfWidth / aspect;

    return cam;
}

class GlSnapshotRenderer final : public SnapshotRenderer {
public:
    explicit GlSnapshotRenderer(const std::string& device) : m_context(device) {
        // If anything below throws, m_context's destructor destroys the context and with it every GL object.
        m_program = linkProgram(Program::Snapshot);
        glCreateVertexArrays(1, &m_vao);
        glCreateBuffers(1, &m_buffer);
        glVertexArrayVertexBuffer(m_vao, 0, m_buffer, 0, sizeof(Vertex));
        glEnableVertexArrayAttrib(m_vao, CULLIDE_SNAPSHOT_ATTR_POSITION);
        glVertexArrayAttribFormat(m_vao, CULLIDE_SNAPSHOT_ATTR_POSITION, 3, GL_FLOAT, GL_FALSE,
                                  offsetof(Vertex, position));
        glVertexArrayAttribBinding(m_vao, CULLIDE_SNAPSHOT_ATTR_POSITION, 0);
        glEnableVertexArrayAttrib(m_vao, CULLIDE_SNAPSHOT_ATTR_COLOR);
        glVertexArrayAttribFormat(m_vao, CULLIDE_SNAPSHOT_ATTR_COLOR, 4, GL_UNSIGNED_BYTE, GL_TRUE,
                                  offsetof(Vertex, rgba));
        glVertexArrayAttribBinding(m_vao, CULLIDE_SNAPSHOT_ATTR_COLOR, 0);
        GLint maxSamples = 0;
        glGetIntegerv(GL_MAX_SAMPLES, &maxSamples);
        m_maxSamples = maxSamples;
        const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
        m_renderer = renderer ? renderer : "?";
        checkGlError("creating the snapshot renderer");
    }

    ~GlSnapshotRenderer() override {
        if (!m_context.tryMakeCurrent()) return;  // the context is gone: so are its objects
        deleteTargets();
        glDeleteBuffers(1, &m_buffer);
        glDeleteVertexArrays(1, &m_vao);
        glDeleteProgram(m_program);
    }

    std::string renderer() const override { return m_renderer; }

    Image render(const std::vector<SnapshotItem>& items, const SnapshotView& view) override {
        validateView(view);
        for (std::size_t i = 0; i < items.size(); ++i) {
            if (items[i].mesh == nullptr)
                throw std::invalid_argument("SnapshotRenderer: item " + std::to_string(i) + " has no mesh");
            requireColour(items[i].color, "the colour of item " + std::to_string(i));
        }

        // The frame defaults to the bounds of what can be drawn; the camera needs it before the vertices are made
        // (they are stored relative to its centre).
        Aabb geometry;
        for (const SnapshotItem& item : items) {
            for (const TriangleIndices& t : item.mesh->triangles) {
                if (!drawable(*item.mesh, t)) continue;
                for (std::uint32_t v : t) geometry.grow(item.mesh->vertices[v]);
            }
        }
        m_vertices.clear();
        Camera camera;
        if (view.frame.has_value() || !geometry.isEmpty()) {
            camera = fitCamera(view, view.frame.value_or(geometry));
            buildVertices(items, view, camera);
        }

        m_context.makeCurrent();
        ensureTargets(view.width, view.height);
        const GLuint drawTarget = m_samples > 1 ? m_multisampleFramebuffer : m_framebuffer;
        const float background[4] = {view.background[0], view.background[1], view.background[2], 1.0f};
        const float depth = 1.0f;
        glClearNamedFramebufferfv(drawTarget, GL_COLOR, 0, background);
        glClearNamedFramebufferfv(drawTarget, GL_DEPTH, 0, &depth);
        if (!m_vertices.empty()) {
            uploadVertices();
            float matrix[16];
            camera.matrix(matrix);
            const Vec3 light = (camera.toViewer + 0.5 * camera.up - 0.3 * camera.right).normalized();
            glProgramUniformMatrix4fv(m_program, CULLIDE_SNAPSHOT_LOC_VIEW_PROJ, 1, GL_TRUE, matrix);
            glProgramUniform3f(m_program, CULLIDE_SNAPSHOT_LOC_LIGHT, static_cast<float>(light.x()),
                               static_cast<float>(light.y()), static_cast<float>(light.z()));
            glProgramUniform3f(m_program, CULLIDE_SNAPSHOT_LOC_BACKGROUND, view.background[0], view.background[1],
                               view.background[2]);
            glProgramUniform1f(m_program, CULLIDE_SNAPSHOT_LOC_EDGES, kEdgeDarkening);
            glBindFramebuffer(GL_DRAW_FRAMEBUFFER, drawTarget);
            glViewport(0, 0, view.width, view.height);
            glEnable(GL_DEPTH_TEST);
            glDepthFunc(GL_LESS);
            glEnable(GL_DEPTH_CLAMP);
            glDisable(GL_CULL_FACE);  // open soups: both sides are visible
            glDisable(GL_BLEND);
            glUseProgram(m_program);
            glBindVertexArray(m_vao);
            {
                const ThirdPartyLeakScope ignoreMesaDrawLeak;
                glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(m_vertices.size()));
            }
            glBindVertexArray(0);
            glUseProgram(0);
        }
        if (m_samples > 1) {
            // Mesa resolves with a draw of its own: the first raster draw of a process when nothing was drawn.
            const ThirdPartyLeakScope ignoreMesaDrawLeak;
            glBlitNamedFramebuffer(m_multisampleFramebuffer, m_framebuffer, 0, 0, view.width, view.height, 0, 0,
                                   view.width, view.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
        }
        Image image;
        image.width = view.width;
        image.height = view.height;
        const std::size_t rowBytes = 4 * static_cast<std::size_t>(view.width);
        image.rgba.resize(rowBytes * static_cast<std::size_t>(view.height));
        glBindFramebuffer(GL_READ_FRAMEBUFFER, m_framebuffer);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadnPixels(0, 0, view.width, view.height, GL_RGBA, GL_UNSIGNED_BYTE, static_cast<GLsizei>(image.rgba.size()),
                      image.rgba.data());
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        checkGlError("rendering a snapshot");
        // GL's row 0 is the bottom; Image's is the top.
        std::vector<std::uint8_t> row(rowBytes);
        for (std::size_t top = 0, bottom = static_cast<std::size_t>(view.height) - 1; top < bottom; ++top, --bottom) {
            std::uint8_t* a = image.rgba.data() + top * rowBytes;
            std::uint8_t* b = image.rgba.data() + bottom * rowBytes;
            std::memcpy(row.data(), a, rowBytes);
            std::memcpy(a, b, rowBytes);
            std::memcpy(b, row.data(), rowBytes);
        }
        return image;
    }

private:
    /// One vertex per corner of every drawable triangle, coloured by its state (mark > highlight > base).
    /// Also sets the camera's depth range to the depth of the vertices kept.
    void buildVertices(const std::vector<SnapshotItem>& items, const SnapshotView& view, Camera& camera) {
        m_vertices.clear();
        double zMin = std::numeric_limits<double>::infinity(), zMax = -zMin;
        for (const SnapshotItem& item : items) {
            const TriangleMesh& mesh = *item.mesh;
            m_state.assign(mesh.triangles.size(), kBase);
            if (item.highlighted)
                for (std::uint32_t t : *item.highlighted)
                    if (t < m_state.size()) m_state[t] = std::max(m_state[t], kHighlighted);
            if (item.marked)
                for (std::uint32_t t : *item.marked)
                    if (t < m_state.size()) m_state[t] = kMarked;
            const std::uint8_t baseAlpha =
                view.dimUnhighlighted && item.highlighted != nullptr ? toByte(kDimmedOpacity) : 255;
            const std::array<std::uint8_t, 4> colours[3] = {
                {toByte(item.color[0]), toByte(item.color[1]), toByte(item.color[2]), baseAlpha},
                {toByte(view.highlight[0]), toByte(view.highlight[1]), toByte(view.highlight[2]), 255},
                {toByte(view.mark[0]), toByte(view.mark[1]), toByte(view.mark[2]), 255}};
            for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
                const TriangleIndices& tri = mesh.triangles[t];
                if (!drawable(mesh, tri)) continue;
                Vertex corners[3];
                bool finite = true;
                for (int k = 0; k < 3; ++k) {
                    const Vec3 p = mesh.vertices[tri[k]] - camera.centre;
                    for (int c = 0; c < 3; ++c) corners[k].position[c] = static_cast<float>(p[c]);
                    // Finite doubles can still overflow float far from the frame: such a triangle is skipped
                    // rather than handed to the rasterizer as inf/NaN.
                    finite = finite && std::isfinite(corners[k].position[0]) &&
                             std::isfinite(corners[k].position[1]) && std::isfinite(corners[k].position[2]);
                    std::memcpy(corners[k].rgba, colours[m_state[t]].data(), 4);
                }
                if (!finite) continue;
                m_vertices.insert(m_vertices.end(), corners, corners + 3);
                for (std::uint32_t v : tri) {
                    const double z = (mesh.vertices[v] - camera.centre).dot(camera.toViewer);
                    zMin = std::min(zMin, z);
                    zMax = std::max(zMax, z);
                }
            }
        }
        if (!m_vertices.empty()) camera.setDepthRange(zMin, zMax);
        if (m_vertices.size() > static_cast<std::size_t>(std::numeric_limits<GLsizei>::max()))
            throw std::length_error("SnapshotRenderer: more than 715 million triangles in one snapshot");
    }

    void uploadVertices() {
        const std::size_t bytes = m_vertices.size() * sizeof(Vertex);
        if (bytes > m_bufferCapacity) {
            m_bufferCapacity = std::max(bytes, m_bufferCapacity + m_bufferCapacity / 2);
            glNamedBufferData(m_buffer, static_cast<GLsizeiptr>(m_bufferCapacity), nullptr, GL_STREAM_DRAW);
        }
        glNamedBufferSubData(m_buffer, 0, static_cast<GLsizeiptr>(bytes), m_vertices.data());
    }

    /// (Re)creates the render targets for a new image size: 4x multisampled colour + depth resolved into a
    /// single-sample colour target, or single-sample colour + depth when multisampling is off.
    void ensureTargets(int width, int height) {
        if (width == m_width && height == m_height) return;
        deleteTargets();
        m_samples = m_maxSamples >= kSamples && static_cast<long long>(width) * height <= kMaxMultisamplePixels
                        ? kSamples
                        : 1;
        glCreateFramebuffers(1, &m_framebuffer);
        glCreateRenderbuffers(1, &m_colour);
        glNamedRenderbufferStorage(m_colour, GL_RGBA8, width, height);
        glNamedFramebufferRenderbuffer(m_framebuffer, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, m_colour);
        GLuint depthTarget = m_framebuffer;
        if (m_samples > 1) {
            glCreateFramebuffers(1, &m_multisampleFramebuffer);
            glCreateRenderbuffers(1, &m_multisampleColour);
            glNamedRenderbufferStorageMultisample(m_multisampleColour, m_samples, GL_RGBA8, width, height);
            glNamedFramebufferRenderbuffer(m_multisampleFramebuffer, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                                           m_multisampleColour);
            depthTarget = m_multisampleFramebuffer;
        }
        glCreateRenderbuffers(1, &m_depth);
        if (m_samples > 1) {
            glNamedRenderbufferStorageMultisample(m_depth, m_samples, GL_DEPTH_COMPONENT24, width, height);
        } else {
            glNamedRenderbufferStorage(m_depth, GL_DEPTH_COMPONENT24, width, height);
        }
        glNamedFramebufferRenderbuffer(depthTarget, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, m_depth);
        // Without depth bits the depth test passes everything and the last triangle drawn shows: refuse.
        GLint depthBits = 0;
        glGetNamedFramebufferAttachmentParameteriv(depthTarget, GL_DEPTH_ATTACHMENT,
                                                   GL_FRAMEBUFFER_ATTACHMENT_DEPTH_SIZE, &depthBits);
        if (depthBits < 16) {
            deleteTargets();
            throw std::runtime_error("cullide: the snapshot depth buffer has " + std::to_string(depthBits) +
                                     " bits (" + std::to_string(m_samples) + " samples)");
        }
        for (GLuint fb : {m_framebuffer, m_multisampleFramebuffer}) {
            if (fb == 0) continue;
            const GLenum status = glCheckNamedFramebufferStatus(fb, GL_DRAW_FRAMEBUFFER);
            if (status != GL_FRAMEBUFFER_COMPLETE) {
                deleteTargets();
                throw std::runtime_error("cullide: snapshot framebuffer incomplete (status " +
                                         std::to_string(status) + ") at " + std::to_string(width) + "x" +
                                         std::to_string(height));
            }
        }
        checkGlError("creating the snapshot render targets");
        m_width = width;
        m_height = height;
    }

    void deleteTargets() {
        glDeleteFramebuffers(1, &m_framebuffer);
        glDeleteFramebuffers(1, &m_multisampleFramebuffer);
        glDeleteRenderbuffers(1, &m_colour);
        glDeleteRenderbuffers(1, &m_multisampleColour);
        glDeleteRenderbuffers(1, &m_depth);
        m_framebuffer = m_multisampleFramebuffer = m_colour = m_multisampleColour = m_depth = 0;
        m_width = m_height = 0;
    }

    EglContext m_context;  // first: destroyed last, taking every GL object with it
    std::string m_renderer;
    GLuint m_program = 0;
    GLuint m_vao = 0;
    GLuint m_buffer = 0;
    std::size_t m_bufferCapacity = 0;
    GLint m_maxSamples = 0;
    int m_samples = 1;
    int m_width = 0;
    int m_height = 0;
    GLuint m_framebuffer = 0;             // single-sample colour, read back
    GLuint m_colour = 0;
    GLuint m_multisampleFramebuffer = 0;  // drawn into when multisampling
    GLuint m_multisampleColour = 0;
    GLuint m_depth = 0;                   // attached to whichever framebuffer is drawn into
    std::vector<Vertex> m_vertices;
    std::vector<std::uint8_t> m_state;    // per triangle of the current item: kBase / kHighlighted / kMarked
};

}  // namespace
}  // namespace gl

std::unique_ptr<SnapshotRenderer> SnapshotRenderer::create(const std::string& device) {
    return std::make_unique<gl::GlSnapshotRenderer>(device);
}

}  // namespace cullide
