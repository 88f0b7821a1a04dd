//! Readback of a rendered target, rows padded to 256 bytes stripped.

use super::pipelines::*;
use super::*;

/// Copies the resolved target into the readback buffer (rows padded to
/// `COPY_BYTES_PER_ROW_ALIGNMENT`, 256), maps it and strips the padding, into texels of type
/// `T` (bytes, or the 32-bit texels of the ID and depth targets: no second copy). Adds the
/// time blocked waiting for the GPU (the poll until the buffer is mapped) to `gpu_wait`.
pub(super) fn read_texture<T: bytemuck::Pod>(
    gpu: &Gpu,
    mut encoder: wgpu::CommandEncoder,
    targets: &Targets,
    gpu_wait: &mut std::time::Duration,
) -> Result<Vec<T>, RenderError> {
    let (w, h) = targets.size;
    let (unpadded, padded) = (targets.row_bytes, targets.padded_row_bytes);
    let (texture, buffer) = (&targets.resolved, &targets.readback);
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    gpu.queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    let waiting = std::time::Instant::now();
    let polled = gpu.device.poll(wgpu::PollType::wait_indefinitely());
    *gpu_wait += waiting.elapsed();
    polled.map_err(|e| RenderError::Readback(e.to_string()))?;
    rx.recv()
        .map_err(|e| RenderError::Readback(e.to_string()))?
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    let bytes = (unpadded * h) as usize;
    let mut out: Vec<T> = vec![T::zeroed(); bytes / size_of::<T>()];
    let copied = buffer.get_mapped_range(..).map(|data| {
        let dst: &mut [u8] = bytemuck::cast_slice_mut(&mut out);
        if padded == unpadded {
            dst.copy_from_slice(&data[..bytes]);
        } else {
            let rows = data.chunks_exact(padded as usize);
            for (to, row) in dst.chunks_exact_mut(unpadded as usize).zip(rows) {
                to.copy_from_slice(&row[..unpadded as usize]);
            }
        }
    });
    // Unmapped whatever happened: the buffer is reused by the next frame.
    buffer.unmap();
    copied.map_err(|e| RenderError::Readback(e.to_string()))?;
    Ok(out)
}
