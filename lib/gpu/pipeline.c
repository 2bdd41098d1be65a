/* Pipeline layouts with push descriptors, compute and graphics pipelines (dynamic rendering),
 * and the push-descriptor write list a pass fills at record time. */
#include "gpu/gpu.h"

static enum rb_status make_module(struct rb_gpu *gpu, const uint32_t *spv, size_t bytes,
                                  const char *name, VkShaderModule *out, struct rb_err *err)
{
    VkShaderModuleCreateInfo ci = {
        .sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO,
        .codeSize = bytes,
        .pCode = spv,
    };
    VkResult vr = vkCreateShaderModule(gpu->device, &ci, NULL, out);
    if (vr < 0)
        return rb_gpu_fail(err, vr, "vkCreateShaderModule", name);
    return RB_OK;
}

enum rb_status rb_gpu_layout_check(const VkPhysicalDeviceLimits *limits,
                                   uint32_t max_push_descriptors, const VkDescriptorType *types,
                                   uint32_t count, struct rb_err *err)
{
    /* What counts against each per-stage limit, as the Vulkan spec's limits chapter says. Every
     * binding is visible to all stages, so each stage sees the whole set. (Color attachments
     * also count against maxPerStageResources in a fragment shader; no pass comes close.) */
    uint32_t samplers = 0, uniform_buffers = 0, storage_buffers = 0, sampled_images = 0;
    uint32_t storage_images = 0, input_attachments = 0, resources = 0;
    for (uint32_t i = 0; i < count; i++) {
        switch (types[i]) {
        case VK_DESCRIPTOR_TYPE_SAMPLER: samplers++; break;
        case VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER:
            samplers++;
            sampled_images++;
            break;
        case VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE:
        case VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER: sampled_images++; break;
        case VK_DESCRIPTOR_TYPE_STORAGE_IMAGE:
        case VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER: storage_images++; break;
        case VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER:
        case VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC: uniform_buffers++; break;
        case VK_DESCRIPTOR_TYPE_STORAGE_BUFFER:
        case VK_DESCRIPTOR_TYPE_STORAGE_BUFFER_DYNAMIC: storage_buffers++; break;
        case VK_DESCRIPTOR_TYPE_INPUT_ATTACHMENT: input_attachments++; break;
        default:
            return rb_errf(err, RB_E_UNSUPPORTED,
                           "binding %u: descriptor type %d has no limit check here", i,
                           (int)types[i]);
        }
        if (types[i] != VK_DESCRIPTOR_TYPE_SAMPLER) /* a sampler alone is not a resource */
            resources++;
    }
    const struct {
        const char *what, *limit;
        uint32_t used, max;
    } checks[] = {
        {"bindings", "maxPushDescriptors", count, max_push_descriptors},
        {"bindings", "RB_GPU_MAX_BINDINGS", count, RB_GPU_MAX_BINDINGS},
        {"samplers", "maxPerStageDescriptorSamplers", samplers,
         limits->maxPerStageDescriptorSamplers},
        {"uniform buffers", "maxPerStageDescriptorUniformBuffers", uniform_buffers,
         limits->maxPerStageDescriptorUniformBuffers},
        {"storage buffers", "maxPerStageDescriptorStorageBuffers", storage_buffers,
         limits->maxPerStageDescriptorStorageBuffers},
        {"sampled images", "maxPerStageDescriptorSampledImages", sampled_images,
         limits->maxPerStageDescriptorSampledImages},
        {"storage images", "maxPerStageDescriptorStorageImages", storage_images,
         limits->maxPerStageDescriptorStorageImages},
        {"input attachments", "maxPerStageDescriptorInputAttachments", input_attachments,
         limits->maxPerStageDescriptorInputAttachments},
        {"resources", "maxPerStageResources", resources, limits->maxPerStageResources},
    };
    for (size_t i = 0; i < sizeof(checks) / sizeof(checks[0]); i++)
        if (checks[i].used > checks[i].max)
            return rb_errf(err, RB_E_UNSUPPORTED,
                           "descriptor set layout has %u %s, more than %s (%u)", checks[i].used,
                           checks[i].what, checks[i].limit, checks[i].max);
    return RB_OK;
}

enum rb_status rb_gpu_layout_init(struct rb_gpu *gpu, const VkDescriptorType *types, uint32_t count,
                                  uint32_t push_bytes, struct rb_gpu_layout *out,
                                  struct rb_err *err)
{
    VkPhysicalDevicePushDescriptorPropertiesKHR push_props = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PUSH_DESCRIPTOR_PROPERTIES_KHR};
    VkPhysicalDeviceProperties2 props = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2,
                                         .pNext = &push_props};
    vkGetPhysicalDeviceProperties2(gpu->phys, &props);
    enum rb_status st = rb_gpu_layout_check(&props.properties.limits, push_props.maxPushDescriptors,
                                            types, count, err);
    if (st)
        return st;
    struct rb_gpu_layout l = {.binding_count = count};
    VkDescriptorSetLayoutBinding bindings[RB_GPU_MAX_BINDINGS];
    for (uint32_t i = 0; i < count; i++) {
        l.types[i] = types[i];
        bindings[i] = (VkDescriptorSetLayoutBinding){
            .binding = i,
            .descriptorType = types[i],
            .descriptorCount = 1,
            .stageFlags = VK_SHADER_STAGE_ALL,
        };
    }
    VkDescriptorSetLayoutCreateInfo sci = {
        .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
        .flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR,
        .bindingCount = count,
        .pBindings = bindings,
    };
    VkResult vr = vkCreateDescriptorSetLayout(gpu->device, &sci, NULL, &l.set_layout);
    if (vr < 0)
        return rb_gpu_fail(err, vr, "vkCreateDescriptorSetLayout", NULL);
    VkPushConstantRange pc = {.stageFlags = VK_SHADER_STAGE_ALL, .offset = 0, .size = push_bytes};
    VkPipelineLayoutCreateInfo pci = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
        .setLayoutCount = 1,
        .pSetLayouts = &l.set_layout,
        .pushConstantRangeCount = push_bytes ? 1 : 0,
        .pPushConstantRanges = &pc,
    };
    if ((vr = vkCreatePipelineLayout(gpu->device, &pci, NULL, &l.pipeline_layout)) < 0) {
        vkDestroyDescriptorSetLayout(gpu->device, l.set_layout, NULL);
        return rb_gpu_fail(err, vr, "vkCreatePipelineLayout", NULL);
    }
    *out = l;
    return RB_OK;
}

void rb_gpu_layout_release(struct rb_gpu *gpu, struct rb_gpu_layout *layout)
{
    if (!layout)
        return;
    if (layout->pipeline_layout)
        vkDestroyPipelineLayout(gpu->device, layout->pipeline_layout, NULL);
    if (layout->set_layout)
        vkDestroyDescriptorSetLayout(gpu->device, layout->set_layout, NULL);
    *layout = (struct rb_gpu_layout){0};
}

enum rb_status rb_gpu_compute_pipeline(struct rb_gpu *gpu, const uint32_t *spv, size_t spv_bytes,
                                       VkPipelineLayout layout, const char *debug_name,
                                       VkPipeline *out, struct rb_err *err)
{
    VkShaderModule mod = VK_NULL_HANDLE;
    enum rb_status st = make_module(gpu, spv, spv_bytes, debug_name, &mod, err);
    if (st)
        return st;
    VkComputePipelineCreateInfo ci = {
        .sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
        .stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
                  .stage = VK_SHADER_STAGE_COMPUTE_BIT,
                  .module = mod,
                  .pName = "main"},
        .layout = layout,
    };
    VkResult vr = vkCreateComputePipelines(gpu->device, VK_NULL_HANDLE, 1, &ci, NULL, out);
    vkDestroyShaderModule(gpu->device, mod, NULL);
    if (vr < 0)
        return rb_gpu_fail(err, vr, "vkCreateComputePipelines", debug_name);
    rb_gpu_name(gpu, VK_OBJECT_TYPE_PIPELINE, (uint64_t)*out, debug_name);
    return RB_OK;
}

/* Tessellation, when d->tesc is set: its control and evaluation stages go after stages[*count]
 * (the vertex and fragment stages), and *ts says how many vertices make a patch. The caller
 * destroys mods[] whether or not this fails. */
static enum rb_status tessellation_stages(struct rb_gpu *gpu, const struct rb_gpu_graphics_desc *d,
                                          VkShaderModule mods[2],
                                          VkPipelineShaderStageCreateInfo *stages, uint32_t *count,
                                          VkPipelineTessellationStateCreateInfo *ts,
                                          struct rb_err *err)
{
    if (!d->tese)
        RB_BUG("pipeline '%s': a tessellation control stage without an evaluation stage",
               d->debug_name ? d->debug_name : "?");
    enum rb_status st = make_module(gpu, d->tesc, d->tesc_bytes, d->debug_name, &mods[0], err);
    if (st == RB_OK)
        st = make_module(gpu, d->tese, d->tese_bytes, d->debug_name, &mods[1], err);
    if (st)
        return st;
    static const VkShaderStageFlagBits kinds[2] = {VK_SHADER_STAGE_TESSELLATION_CONTROL_BIT,
                                                   VK_SHADER_STAGE_TESSELLATION_EVALUATION_BIT};
    for (int i = 0; i < 2; i++)
        stages[(*count)++] = (VkPipelineShaderStageCreateInfo){
            .sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
            .stage = kinds[i],
            .module = mods[i],
            .pName = "main",
        };
    *ts = (VkPipelineTessellationStateCreateInfo){
        .sType = VK_STRUCTURE_TYPE_PIPELINE_TESSELLATION_STATE_CREATE_INFO,
        .patchControlPoints = d->patch_control_points ? d->patch_control_points : 3,
    };
    return RB_OK;
}

enum rb_status rb_gpu_graphics_pipeline(struct rb_gpu *gpu, const struct rb_gpu_graphics_desc *d,
                                        VkPipeline *out, struct rb_err *err)
{
    VkShaderModule vs = VK_NULL_HANDLE, fs = VK_NULL_HANDLE, tess[2] = {VK_NULL_HANDLE};
    VkPipelineTessellationStateCreateInfo ts = {0};
    enum rb_status st = make_module(gpu, d->vert, d->vert_bytes, d->debug_name, &vs, err);
    if (st == RB_OK)
        st = make_module(gpu, d->frag, d->frag_bytes, d->debug_name, &fs, err);
    if (st)
        goto out;
    VkPipelineShaderStageCreateInfo stages[4] = {
        {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
         .stage = VK_SHADER_STAGE_VERTEX_BIT,
         .module = vs,
         .pName = "main"},
        {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
         .stage = VK_SHADER_STAGE_FRAGMENT_BIT,
         .module = fs,
         .pName = "main"},
    };
    uint32_t stage_count = 2;
    if (d->tesc && (st = tessellation_stages(gpu, d, tess, stages, &stage_count, &ts, err)))
        goto out;
    VkPipelineVertexInputStateCreateInfo vi = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    VkPipelineInputAssemblyStateCreateInfo ia = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO,
        .topology =
            d->tesc ? VK_PRIMITIVE_TOPOLOGY_PATCH_LIST : VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST};
    VkPipelineViewportStateCreateInfo vp = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO,
        .viewportCount = 1,
        .scissorCount = 1};
    VkPipelineRasterizationStateCreateInfo rs = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO,
        .polygonMode = VK_POLYGON_MODE_FILL,
        .cullMode = d->cull,
        .frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE,
        .depthBiasEnable = d->has_depth_bias,
        .lineWidth = 1.0f};
    VkPipelineMultisampleStateCreateInfo ms = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO,
        .rasterizationSamples = VK_SAMPLE_COUNT_1_BIT};
    bool has_depth = d->depth_format != VK_FORMAT_UNDEFINED;
    VkPipelineDepthStencilStateCreateInfo ds = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO,
        .depthTestEnable = has_depth,
        .depthWriteEnable = has_depth && !d->is_depth_equal && !d->is_blend_over,
        .depthCompareOp = d->is_depth_equal ? VK_COMPARE_OP_EQUAL : VK_COMPARE_OP_LESS};
    VkPipelineColorBlendAttachmentState blend[8] = {{0}};
    for (uint32_t i = 0; i < d->color_count && i < 8; i++) {
        blend[i].colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT |
                                  VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
        if (d->is_blend_over) /* rgb' = src.rgb + (1 - src.a) rgb, a' = (1 - src.a) a */
            blend[i] = (VkPipelineColorBlendAttachmentState){
                .blendEnable = VK_TRUE,
                .srcColorBlendFactor = VK_BLEND_FACTOR_ONE,
                .dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA,
                .colorBlendOp = VK_BLEND_OP_ADD,
                .srcAlphaBlendFactor = VK_BLEND_FACTOR_ZERO,
                .dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA,
                .alphaBlendOp = VK_BLEND_OP_ADD,
                .colorWriteMask = blend[i].colorWriteMask};
    }
    VkPipelineColorBlendStateCreateInfo cb = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO,
        .attachmentCount = d->color_count,
        .pAttachments = blend};
    VkDynamicState dyn[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR,
                            VK_DYNAMIC_STATE_DEPTH_BIAS};
    VkPipelineDynamicStateCreateInfo dy = {.sType =
                                               VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO,
                                           .dynamicStateCount = d->has_depth_bias ? 3 : 2,
                                           .pDynamicStates = dyn};
    VkPipelineRenderingCreateInfo ri = {.sType = VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO,
                                        .colorAttachmentCount = d->color_count,
                                        .pColorAttachmentFormats = d->color_formats,
                                        .depthAttachmentFormat = d->depth_format};
    VkGraphicsPipelineCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO,
                                       .pNext = &ri,
                                       .stageCount = stage_count,
                                       .pStages = stages,
                                       .pVertexInputState = &vi,
                                       .pInputAssemblyState = &ia,
                                       .pTessellationState = d->tesc ? &ts : NULL,
                                       .pViewportState = &vp,
                                       .pRasterizationState = &rs,
                                       .pMultisampleState = &ms,
                                       .pDepthStencilState = &ds,
                                       .pColorBlendState = &cb,
                                       .pDynamicState = &dy,
                                       .layout = d->layout};
    VkResult vr = vkCreateGraphicsPipelines(gpu->device, VK_NULL_HANDLE, 1, &ci, NULL, out);
    if (vr < 0)
        st = rb_gpu_fail(err, vr, "vkCreateGraphicsPipelines", d->debug_name);
    else
        rb_gpu_name(gpu, VK_OBJECT_TYPE_PIPELINE, (uint64_t)*out, d->debug_name);
out:
    if (vs)
        vkDestroyShaderModule(gpu->device, vs, NULL);
    if (fs)
        vkDestroyShaderModule(gpu->device, fs, NULL);
    for (int i = 0; i < 2; i++)
        if (tess[i])
            vkDestroyShaderModule(gpu->device, tess[i], NULL);
    return st;
}

/* Claims binding i of b for a write of the given type. */
static VkWriteDescriptorSet *claim(struct rb_gpu_bindings *b, uint32_t i, VkDescriptorType type)
{
    if (i >= RB_GPU_MAX_BINDINGS)
        RB_BUG("binding %u: a push-descriptor set holds at most %u", i, RB_GPU_MAX_BINDINGS);
    if (b->writes[i].sType)
        RB_BUG("binding %u set twice", i);
    if (i >= b->count)
        b->count = i + 1;
    b->writes[i] = (VkWriteDescriptorSet){
        .sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,
        .dstBinding = i,
        .descriptorCount = 1,
        .descriptorType = type,
    };
    return &b->writes[i];
}

void rb_gpu_bindings_set_buffer(struct rb_gpu_bindings *b, uint32_t binding, VkDescriptorType type,
                                const struct rb_gpu_buffer *buf)
{
    VkWriteDescriptorSet *w = claim(b, binding, type);
    b->buffers[binding] = (VkDescriptorBufferInfo){buf->buffer, 0, VK_WHOLE_SIZE};
    w->pBufferInfo = &b->buffers[binding];
}

void rb_gpu_bindings_set_image(struct rb_gpu_bindings *b, uint32_t binding, VkDescriptorType type,
                               VkImageView view, VkSampler sampler, VkImageLayout layout)
{
    VkWriteDescriptorSet *w = claim(b, binding, type);
    b->images[binding] = (VkDescriptorImageInfo){sampler, view, layout};
    w->pImageInfo = &b->images[binding];
}

void rb_gpu_bind_buffer(struct rb_gpu_bindings *b, VkDescriptorType type,
                        const struct rb_gpu_buffer *buf)
{
    rb_gpu_bindings_set_buffer(b, b->count, type, buf);
}

void rb_gpu_bindings_set_buffer_range(struct rb_gpu_bindings *b, uint32_t binding,
                                      VkDescriptorType type, const struct rb_gpu_buffer *buf,
                                      VkDeviceSize offset_bytes, VkDeviceSize range_bytes)
{
    rb_gpu_bindings_set_buffer(b, binding, type, buf);
    b->buffers[binding].offset = offset_bytes;
    b->buffers[binding].range = range_bytes;
}

void rb_gpu_bind_image(struct rb_gpu_bindings *b, VkDescriptorType type, VkImageView view,
                       VkSampler sampler, VkImageLayout layout)
{
    rb_gpu_bindings_set_image(b, b->count, type, view, sampler, layout);
}

void rb_gpu_push_bindings(struct rb_gpu *gpu, VkCommandBuffer cmd, VkPipelineBindPoint point,
                          VkPipelineLayout layout, const struct rb_gpu_bindings *b)
{
    for (uint32_t i = 0; i < b->count; i++)
        if (!b->writes[i].sType)
            RB_BUG("binding %u of %u never set", i, b->count);
    gpu->push_descriptor_set(cmd, point, layout, 0, b->count, b->writes);
}
