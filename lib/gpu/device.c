/* Instance, device selection and validation. The renderer's requirements (API version,
 * features, extensions) are in one table here, with one message per missing item. */
#include "gpu/gpu.h"
#include "gpu/gpu_int.h"

#include <ctype.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* What the loader's VK_ERROR_INCOMPATIBLE_DRIVER means to a user: it found no driver at all, or
 * none of Vulkan 1.3. */
#define NO_DRIVER_HINT                                                                             \
    "no Vulkan 1.3 driver found (VK_ERROR_INCOMPATIBLE_DRIVER): install one, e.g. Mesa's "         \
    "lavapipe (Debian, Ubuntu: mesa-vulkan-drivers) or your GPU vendor's driver"

#define VALIDATION_LAYER "VK_LAYER_KHRONOS_validation"

/* What a device must have; anything missing is named in the error. */
static const char *const required_extensions[] = {
    VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME,
};

/* Vulkan 1.0 features, checked and enabled by name: tessellation for the paraboloid views'
 * curved edges, fragment-stage stores and atomics for the linked-list views, geometry shaders
 * for gl_PrimitiveID in the G-buffer's fragment shader (SPIR-V's PrimitiveId needs the Geometry
 * capability there; no geometry shader runs). */
static const struct {
    size_t offset;
    const char *name;
} required_features[] = {
    {offsetof(VkPhysicalDeviceFeatures, tessellationShader), "tessellationShader"},
    {offsetof(VkPhysicalDeviceFeatures, fragmentStoresAndAtomics), "fragmentStoresAndAtomics"},
    {offsetof(VkPhysicalDeviceFeatures, geometryShader), "geometryShader"},
};

static VkBool32 *feature(VkPhysicalDeviceFeatures *f, size_t i)
{
    return (VkBool32 *)((char *)f + required_features[i].offset);
}

const char *rb_gpu_result_name(VkResult vr)
{
    switch (vr) {
#define R(x)                                                                                       \
    case x: return #x;
        R(VK_SUCCESS)
        R(VK_NOT_READY)
        R(VK_TIMEOUT)
        R(VK_INCOMPLETE)
        R(VK_ERROR_OUT_OF_HOST_MEMORY)
        R(VK_ERROR_OUT_OF_DEVICE_MEMORY)
        R(VK_ERROR_INITIALIZATION_FAILED)
        R(VK_ERROR_DEVICE_LOST)
        R(VK_ERROR_MEMORY_MAP_FAILED)
        R(VK_ERROR_LAYER_NOT_PRESENT)
        R(VK_ERROR_EXTENSION_NOT_PRESENT)
        R(VK_ERROR_FEATURE_NOT_PRESENT)
        R(VK_ERROR_INCOMPATIBLE_DRIVER)
        R(VK_ERROR_TOO_MANY_OBJECTS)
        R(VK_ERROR_FORMAT_NOT_SUPPORTED)
        R(VK_ERROR_FRAGMENTED_POOL)
        R(VK_ERROR_OUT_OF_POOL_MEMORY)
#undef R
    default: return "VK_ERROR_UNKNOWN";
    }
}

enum rb_status rb_gpu_fail(struct rb_err *err, VkResult vr, const char *call, const char *what)
{
    enum rb_status st = vr == VK_ERROR_INITIALIZATION_FAILED || vr == VK_ERROR_INCOMPATIBLE_DRIVER
                            ? RB_E_NODEVICE
                            : RB_E_VULKAN;
    if (what && *what)
        return rb_errf(err, st, "%s '%s': %s", call, what, rb_gpu_result_name(vr));
    return rb_errf(err, st, "%s: %s", call, rb_gpu_result_name(vr));
}

static VKAPI_ATTR VkBool32 VKAPI_CALL on_debug(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                               VkDebugUtilsMessageTypeFlagsEXT types,
                                               const VkDebugUtilsMessengerCallbackDataEXT *data,
                                               void *user)
{
    struct rb_gpu *gpu = user;
    bool counts = (types & VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT) &&
                  severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT;
    if (counts) {
        if (gpu->validation_messages++ == 0)
            rb_strlcpy(gpu->first_validation_message, data->pMessage ? data->pMessage : "?",
                       sizeof(gpu->first_validation_message));
        rb_log(RB_LOG_ERROR, "validation: %s", data->pMessage ? data->pMessage : "?");
    } else {
        rb_log(RB_LOG_DEBUG, "vulkan: %s", data->pMessage ? data->pMessage : "?");
    }
    return VK_FALSE;
}

static bool has_layer(const char *name)
{
    uint32_t n = 0;
    vkEnumerateInstanceLayerProperties(&n, NULL);
    VkLayerProperties *props = calloc(n ? n : 1, sizeof(*props));
    bool found = false;
    if (props && vkEnumerateInstanceLayerProperties(&n, props) >= 0)
        for (uint32_t i = 0; i < n && !found; i++)
            found = strcmp(props[i].layerName, name) == 0;
    free(props);
    return found;
}

static bool has_instance_extension(const char *name)
{
    uint32_t n = 0;
    vkEnumerateInstanceExtensionProperties(NULL, &n, NULL);
    VkExtensionProperties *props = calloc(n ? n : 1, sizeof(*props));
    bool found = false;
    if (props && vkEnumerateInstanceExtensionProperties(NULL, &n, props) >= 0)
        for (uint32_t i = 0; i < n && !found; i++)
            found = strcmp(props[i].extensionName, name) == 0;
    free(props);
    return found;
}

static VkResult create_instance(bool validate, bool debug_utils, VkInstance *out)
{
    const char *layers[] = {VALIDATION_LAYER};
    const char *exts[2];
    uint32_t ext_count = 0;
    if (debug_utils)
        exts[ext_count++] = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    /* Validation checks synchronization too: a missing barrier between passes is a hazard the
     * layer reports like any other error (the layer provides the extension itself). */
    static const VkValidationFeatureEnableEXT enables[] = {
        VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT,
    };
    VkValidationFeaturesEXT features = {
        .sType = VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT,
        .enabledValidationFeatureCount = sizeof(enables) / sizeof(enables[0]),
        .pEnabledValidationFeatures = enables,
    };
    if (validate)
        exts[ext_count++] = VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME;
    VkApplicationInfo app = {
        .sType = VK_STRUCTURE_TYPE_APPLICATION_INFO,
        .pApplicationName = "raybundle",
        .applicationVersion = VK_MAKE_VERSION(0, 1, 0),
        .pEngineName = "raybundle",
        .apiVersion = VK_API_VERSION_1_3,
    };
    VkInstanceCreateInfo ci = {
        .sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO,
        .pNext = validate ? &features : NULL,
        .pApplicationInfo = &app,
        .enabledLayerCount = validate ? 1 : 0,
        .ppEnabledLayerNames = layers,
        .enabledExtensionCount = ext_count,
        .ppEnabledExtensionNames = exts,
    };
    return vkCreateInstance(&ci, NULL, out);
}

/* Lists what a device lacks, separated by ", "; empty when it has everything. */
static void missing_requirements(VkPhysicalDevice phys, char *out, size_t size)
{
    out[0] = '\0';
    VkPhysicalDeviceProperties props;
    vkGetPhysicalDeviceProperties(phys, &props);
    size_t len = 0;
#define MISSING(...)                                                                               \
    (len += (size_t)snprintf(out + len, len < size ? size - len : 0, "%s", len ? ", " : ""),       \
     len += (size_t)snprintf(out + len, len < size ? size - len : 0, __VA_ARGS__))
    if (props.apiVersion < VK_API_VERSION_1_3)
        MISSING("Vulkan 1.3 (has %u.%u)", VK_API_VERSION_MAJOR(props.apiVersion),
                VK_API_VERSION_MINOR(props.apiVersion));
    uint32_t n = 0;
    vkEnumerateDeviceExtensionProperties(phys, NULL, &n, NULL);
    VkExtensionProperties *exts = calloc(n ? n : 1, sizeof(*exts));
    if (exts)
        vkEnumerateDeviceExtensionProperties(phys, NULL, &n, exts);
    for (size_t r = 0; r < sizeof(required_extensions) / sizeof(required_extensions[0]); r++) {
        bool found = false;
        for (uint32_t i = 0; exts && i < n && !found; i++)
            found = strcmp(exts[i].extensionName, required_extensions[r]) == 0;
        if (!found)
            MISSING("%s", required_extensions[r]);
    }
    free(exts);
    VkPhysicalDeviceVulkan12Features f12 = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    VkPhysicalDeviceVulkan13Features f13 = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES, .pNext = &f12};
    VkPhysicalDeviceFeatures2 f2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2,
                                    .pNext = &f13};
    if (props.apiVersion >= VK_API_VERSION_1_3) {
        vkGetPhysicalDeviceFeatures2(phys, &f2);
        if (!f13.dynamicRendering)
            MISSING("dynamicRendering");
        if (!f13.synchronization2)
            MISSING("synchronization2");
        if (!f12.bufferDeviceAddress) /* the scene's arrays (rb_gpu_buffer_desc.is_addressed) */
            MISSING("bufferDeviceAddress");
        for (size_t i = 0; i < sizeof(required_features) / sizeof(required_features[0]); i++)
            if (!*feature(&f2.features, i))
                MISSING("%s", required_features[i].name);
    }
    uint32_t qn = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(phys, &qn, NULL);
    VkQueueFamilyProperties *qf = calloc(qn ? qn : 1, sizeof(*qf));
    bool has_queue = false;
    if (qf) {
        vkGetPhysicalDeviceQueueFamilyProperties(phys, &qn, qf);
        for (uint32_t i = 0; i < qn && !has_queue; i++)
            has_queue = (qf[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) &&
                        (qf[i].queueFlags & VK_QUEUE_COMPUTE_BIT) && qf[i].timestampValidBits;
    }
    free(qf);
    if (!has_queue)
        MISSING("a graphics+compute queue with timestamps");
#undef MISSING
}

static bool is_lavapipe(const VkPhysicalDeviceProperties *p)
{
    return p->deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU || strstr(p->deviceName, "llvmpipe");
}

static bool name_matches(const char *name, const char *want)
{
    size_t n = strlen(want);
    for (const char *p = name; *p; p++) {
        size_t i = 0;
        while (i < n && p[i] && tolower((unsigned char)p[i]) == tolower((unsigned char)want[i]))
            i++;
        if (i == n)
            return true;
    }
    return false;
}

static enum rb_status pick_device(VkInstance inst, const char *want, VkPhysicalDevice *out,
                                  struct rb_err *err)
{
    uint32_t n = 0;
    VkResult vr = vkEnumeratePhysicalDevices(inst, &n, NULL);
    if (vr < 0)
        return rb_gpu_fail(err, vr, "vkEnumeratePhysicalDevices", NULL);
    if (n == 0)
        return rb_errf(err, RB_E_NODEVICE,
                       "no Vulkan device found (install mesa-vulkan-drivers for lavapipe)");
    VkPhysicalDevice *devs = calloc(n, sizeof(*devs));
    if (!devs)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    vkEnumeratePhysicalDevices(inst, &n, devs);
    enum rb_status st = RB_OK;
    int chosen = -1;
    char *end = NULL;
    long index = want ? strtol(want, &end, 10) : -1;
    if (want && end && *end == '\0' && *want) {
        if (index < 0 || index >= (long)n)
            st =
                rb_errf(err, RB_E_NODEVICE, "device index %ld out of range (%u devices)", index, n);
        chosen = (int)index;
    } else {
        for (uint32_t i = 0; i < n && chosen < 0; i++) {
            VkPhysicalDeviceProperties p;
            vkGetPhysicalDeviceProperties(devs[i], &p);
            if (want ? name_matches(p.deviceName, want) : is_lavapipe(&p))
                chosen = (int)i;
        }
        if (chosen < 0 && want)
            st = rb_errf(err, RB_E_NODEVICE, "no device matches '%s' (see 'raybundle info')", want);
        if (chosen < 0 && !want) {
            rb_log(RB_LOG_WARN, "lavapipe not found; using device 0");
            chosen = 0;
        }
    }
    if (st == RB_OK) {
        char missing[512];
        missing_requirements(devs[chosen], missing, sizeof(missing));
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(devs[chosen], &p);
        if (missing[0])
            st = rb_errf(err, RB_E_NODEVICE, "device '%s' lacks: %s", p.deviceName, missing);
        else
            *out = devs[chosen];
    }
    free(devs);
    return st;
}

static void describe_driver(VkPhysicalDevice phys, char *out, size_t size)
{
    VkPhysicalDeviceDriverProperties drv = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
    VkPhysicalDeviceProperties2 p2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2,
                                      .pNext = &drv};
    vkGetPhysicalDeviceProperties2(phys, &p2);
    size_t n = rb_strlcpy(out, drv.driverName, size);
    if (n + 1 < size) {
        out[n] = ' ';
        rb_strlcpy(out + n + 1, drv.driverInfo, size - n - 1);
    }
}

enum rb_status rb_gpu_create(const struct rb_gpu_desc *desc, struct rb_gpu **out,
                             struct rb_err *err)
{
    enum rb_status st = RB_OK;
    VkResult vr;
    struct rb_gpu *gpu = calloc(1, sizeof(*gpu));
    if (!gpu)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    gpu->validate = desc->validate;
    if (gpu->validate && !has_layer(VALIDATION_LAYER)) {
        st = rb_errf(err, RB_E_NODEVICE,
                     "validation requested but %s is not installed (vulkan-validationlayers)",
                     VALIDATION_LAYER);
        goto fail;
    }
    gpu->has_debug_utils = has_instance_extension(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    vr = create_instance(gpu->validate, gpu->has_debug_utils, &gpu->instance);
    if (vr < 0) {
        st = rb_gpu_fail(err, vr, "vkCreateInstance", NULL);
        if (vr == VK_ERROR_INCOMPATIBLE_DRIVER)
            st = rb_errf(err, RB_E_NODEVICE, "%s", NO_DRIVER_HINT);
        goto fail;
    }
    if (gpu->has_debug_utils) {
        PFN_vkCreateDebugUtilsMessengerEXT create_messenger =
            (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(
                gpu->instance, "vkCreateDebugUtilsMessengerEXT");
        VkDebugUtilsMessengerCreateInfoEXT mci = {
            .sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT,
            .messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                               VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
            .messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                           VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                           VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
            .pfnUserCallback = on_debug,
            .pUserData = gpu,
        };
        if (create_messenger)
            create_messenger(gpu->instance, &mci, NULL, &gpu->messenger);
        gpu->begin_label = (PFN_vkCmdBeginDebugUtilsLabelEXT)vkGetInstanceProcAddr(
            gpu->instance, "vkCmdBeginDebugUtilsLabelEXT");
        gpu->end_label = (PFN_vkCmdEndDebugUtilsLabelEXT)vkGetInstanceProcAddr(
            gpu->instance, "vkCmdEndDebugUtilsLabelEXT");
        gpu->set_object_name = (PFN_vkSetDebugUtilsObjectNameEXT)vkGetInstanceProcAddr(
            gpu->instance, "vkSetDebugUtilsObjectNameEXT");
    }

    st = pick_device(gpu->instance, desc->device, &gpu->phys, err);
    if (st)
        goto fail;
    vkGetPhysicalDeviceProperties(gpu->phys, &gpu->props);
    vkGetPhysicalDeviceMemoryProperties(gpu->phys, &gpu->mem_props);
    rb_gpu_read_limits(gpu);
    rb_strlcpy(gpu->device_name, gpu->props.deviceName, sizeof(gpu->device_name));
    describe_driver(gpu->phys, gpu->driver, sizeof(gpu->driver));
    gpu->is_lavapipe = is_lavapipe(&gpu->props);
    const VkMemoryPropertyFlags unified = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT |
                                          VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                          VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
    for (uint32_t i = 0; i < gpu->mem_props.memoryTypeCount; i++)
        if ((gpu->mem_props.memoryTypes[i].propertyFlags & unified) == unified)
            gpu->is_unified_memory = true;
    const char *staged = getenv("RB_GPU_STAGED_READBACK");
    if (staged && !strcmp(staged, "1"))
        gpu->is_unified_memory = false;
    gpu->timestamp_period_ns = gpu->props.limits.timestampPeriod;

    uint32_t qn = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(gpu->phys, &qn, NULL);
    VkQueueFamilyProperties qf[16];
    if (qn > 16)
        qn = 16;
    vkGetPhysicalDeviceQueueFamilyProperties(gpu->phys, &qn, qf);
    gpu->queue_family = UINT32_MAX;
    for (uint32_t i = 0; i < qn && gpu->queue_family == UINT32_MAX; i++)
        if ((qf[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) &&
            (qf[i].queueFlags & VK_QUEUE_COMPUTE_BIT) && qf[i].timestampValidBits) {
            gpu->queue_family = i;
            gpu->timestamp_mask = qf[i].timestampValidBits >= 64
                                      ? UINT64_MAX
                                      : ((uint64_t)1 << qf[i].timestampValidBits) - 1;
        }

    float prio = 1.0f;
    VkDeviceQueueCreateInfo qci = {
        .sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO,
        .queueFamilyIndex = gpu->queue_family,
        .queueCount = 1,
        .pQueuePriorities = &prio,
    };
    VkPhysicalDeviceVulkan12Features f12 = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES,
        .bufferDeviceAddress = VK_TRUE,
    };
    VkPhysicalDeviceVulkan13Features f13 = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES,
        .pNext = &f12,
        .dynamicRendering = VK_TRUE,
        .synchronization2 = VK_TRUE,
    };
    VkPhysicalDeviceFeatures2 f2 = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2,
        .pNext = &f13,
    };
    for (size_t i = 0; i < sizeof(required_features) / sizeof(required_features[0]); i++)
        *feature(&f2.features, i) = VK_TRUE;
    VkDeviceCreateInfo dci = {
        .sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO,
        .pNext = &f2,
        .queueCreateInfoCount = 1,
        .pQueueCreateInfos = &qci,
        .enabledExtensionCount = sizeof(required_extensions) / sizeof(required_extensions[0]),
        .ppEnabledExtensionNames = required_extensions,
    };
    vr = vkCreateDevice(gpu->phys, &dci, NULL, &gpu->device);
    if (vr < 0) {
        st = rb_gpu_fail(err, vr, "vkCreateDevice", gpu->device_name);
        goto fail;
    }
    vkGetDeviceQueue(gpu->device, gpu->queue_family, 0, &gpu->queue);
    gpu->push_descriptor_set = (PFN_vkCmdPushDescriptorSetKHR)vkGetDeviceProcAddr(
        gpu->device, "vkCmdPushDescriptorSetKHR");

    VkCommandPoolCreateInfo pci = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
        .flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
        .queueFamilyIndex = gpu->queue_family,
    };
    if ((vr = vkCreateCommandPool(gpu->device, &pci, NULL, &gpu->pool)) < 0) {
        st = rb_gpu_fail(err, vr, "vkCreateCommandPool", NULL);
        goto fail;
    }
    VkCommandBufferAllocateInfo cai = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
        .commandPool = gpu->pool,
        .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
        .commandBufferCount = 1,
    };
    if ((vr = vkAllocateCommandBuffers(gpu->device, &cai, &gpu->cmd)) < 0) {
        st = rb_gpu_fail(err, vr, "vkAllocateCommandBuffers", NULL);
        goto fail;
    }
    VkFenceCreateInfo fci = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    if ((vr = vkCreateFence(gpu->device, &fci, NULL, &gpu->fence)) < 0) {
        st = rb_gpu_fail(err, vr, "vkCreateFence", NULL);
        goto fail;
    }
    struct {
        VkSamplerAddressMode mode_u, mode_v;
        VkFilter filter;
        VkSampler *out;
        const char *name;
    } samplers[] = {
        {VK_SAMPLER_ADDRESS_MODE_REPEAT, VK_SAMPLER_ADDRESS_MODE_REPEAT, VK_FILTER_LINEAR,
         &gpu->linear_sampler, "linear"},
        {VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
         VK_FILTER_LINEAR, &gpu->clamp_sampler, "clamp"},
        {VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
         VK_FILTER_NEAREST, &gpu->nearest_sampler, "nearest"},
        {VK_SAMPLER_ADDRESS_MODE_REPEAT, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, VK_FILTER_LINEAR,
         &gpu->env_sampler, "environment"},
    };
    for (size_t i = 0; i < sizeof(samplers) / sizeof(samplers[0]); i++) {
        VkSamplerCreateInfo sci = {
            .sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO,
            .magFilter = samplers[i].filter,
            .minFilter = samplers[i].filter,
            .mipmapMode = samplers[i].filter == VK_FILTER_LINEAR ? VK_SAMPLER_MIPMAP_MODE_LINEAR
                                                                 : VK_SAMPLER_MIPMAP_MODE_NEAREST,
            .addressModeU = samplers[i].mode_u,
            .addressModeV = samplers[i].mode_v,
            .addressModeW = samplers[i].mode_v,
            .maxLod = VK_LOD_CLAMP_NONE,
        };
        if ((vr = vkCreateSampler(gpu->device, &sci, NULL, samplers[i].out)) < 0) {
            st = rb_gpu_fail(err, vr, "vkCreateSampler", samplers[i].name);
            goto fail;
        }
    }
    rb_log(RB_LOG_INFO, "device: %s (%s)", gpu->device_name, gpu->driver);
    *out = gpu;
    return RB_OK;
fail:
    rb_gpu_destroy(gpu);
    return st;
}

void rb_gpu_destroy(struct rb_gpu *gpu)
{
    if (!gpu)
        return;
    if (gpu->device) {
        vkDeviceWaitIdle(gpu->device);
        vkDestroySampler(gpu->device, gpu->env_sampler, NULL);
        vkDestroySampler(gpu->device, gpu->nearest_sampler, NULL);
        vkDestroySampler(gpu->device, gpu->clamp_sampler, NULL);
        vkDestroySampler(gpu->device, gpu->linear_sampler, NULL);
        rb_gpu_queries_release(gpu);
        vkDestroyFence(gpu->device, gpu->fence, NULL);
        vkDestroyCommandPool(gpu->device, gpu->pool, NULL);
        vkDestroyDevice(gpu->device, NULL);
    }
    if (gpu->messenger) {
        PFN_vkDestroyDebugUtilsMessengerEXT destroy_messenger =
            (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(
                gpu->instance, "vkDestroyDebugUtilsMessengerEXT");
        if (destroy_messenger)
            destroy_messenger(gpu->instance, gpu->messenger, NULL);
    }
    if (gpu->instance)
        vkDestroyInstance(gpu->instance, NULL);
    free(gpu);
}

enum rb_status rb_gpu_check_validation(struct rb_gpu *gpu, struct rb_err *err)
{
    if (gpu->validation_messages)
        return rb_errf(err, RB_E_VULKAN, "%u validation message(s); first: %s",
                       gpu->validation_messages, gpu->first_validation_message);
    return RB_OK;
}

void rb_gpu_name(struct rb_gpu *gpu, VkObjectType type, uint64_t handle, const char *name)
{
    if (!gpu->set_object_name || !name || !handle)
        return;
    VkDebugUtilsObjectNameInfoEXT info = {
        .sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_OBJECT_NAME_INFO_EXT,
        .objectType = type,
        .objectHandle = handle,
        .pObjectName = name,
    };
    gpu->set_object_name(gpu->device, &info);
}

static const char *type_name(VkPhysicalDeviceType t)
{
    switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
    default: return "other";
    }
}

enum rb_status rb_gpu_print_devices(FILE *f, struct rb_err *err)
{
    VkInstance inst = VK_NULL_HANDLE;
    VkResult vr = create_instance(false, false, &inst);
    if (vr == VK_ERROR_INCOMPATIBLE_DRIVER)
        return rb_errf(err, RB_E_NODEVICE, "%s", NO_DRIVER_HINT);
    if (vr < 0)
        return rb_errf(err, RB_E_NODEVICE, "cannot create a Vulkan instance: %s",
                       rb_gpu_result_name(vr));
    uint32_t n = 0;
    vkEnumeratePhysicalDevices(inst, &n, NULL);
    VkPhysicalDevice *devs = calloc(n ? n : 1, sizeof(*devs));
    if (!devs) {
        vkDestroyInstance(inst, NULL);
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    }
    vkEnumeratePhysicalDevices(inst, &n, devs);
    fprintf(f, "validation layer: %s\n", has_layer(VALIDATION_LAYER) ? "available" : "missing");
    fprintf(f, "devices: %u\n", n);
    for (uint32_t i = 0; i < n; i++) {
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(devs[i], &p);
        char drv[256], missing[512];
        describe_driver(devs[i], drv, sizeof(drv));
        missing_requirements(devs[i], missing, sizeof(missing));
        fprintf(f, "[%u] %s%s\n", i, p.deviceName, is_lavapipe(&p) ? " (default)" : "");
        fprintf(f, "    type: %s\n", type_name(p.deviceType));
        fprintf(f, "    api: %u.%u.%u\n", VK_API_VERSION_MAJOR(p.apiVersion),
                VK_API_VERSION_MINOR(p.apiVersion), VK_API_VERSION_PATCH(p.apiVersion));
        fprintf(f, "    driver: %s (version 0x%x)\n", drv, p.driverVersion);
        fprintf(f, "    timestamp period: %g ns\n", p.limits.timestampPeriod);
        fprintf(f, "    max storage buffer range: %u bytes\n", p.limits.maxStorageBufferRange);
        fprintf(f, "    max color attachments: %u\n", p.limits.maxColorAttachments);
        fprintf(f, "    uses: Vulkan 1.3, dynamicRendering, synchronization2, bufferDeviceAddress");
        for (size_t k = 0; k < sizeof(required_features) / sizeof(required_features[0]); k++)
            fprintf(f, ", %s", required_features[k].name);
        fprintf(f, ", %s\n", VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME);
        fprintf(f, "    usable: %s%s\n", missing[0] ? "no, lacks " : "yes", missing);
    }
    free(devs);
    vkDestroyInstance(inst, NULL);
    return RB_OK;
}
